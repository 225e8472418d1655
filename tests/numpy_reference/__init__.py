"""The vectorised numpy implementations the compiled kernels replaced, kept
only as independent oracles: the equivalence tests (test_detection_kernels,
test_event_sleep_kernels) check the compiled stages give their results."""
