"""`physics-bench`: the accuracy, stability, cost and scale evidence for physics_core.

Each study writes Markdown tables and log–log PNG plots under
`benchmarks/results/` (or `--out DIR`); `physics-bench all` also refreshes
`README_results.md` and the results section of the README.
"""
