"""Keeping sim time in step with wall time scaled by the real-time factor."""

import math


MIN_TICK_S = 0.002
# At real_time_factor 0 the node steps in a chain of executor tasks
# (node.PhysicsNode._free_run) and the timer only starts that chain: its
# period is how soon stepping resumes after a pause or a reset ends it. It is
# longer than a step budget (node.TICK_BUDGET_S, 20 ms), so the timer is not
# due again each time a budget ends (a timer always due starves rclpy's
# EventsExecutor of everything else).
FREE_RUN_CHECK_S = 0.05


class StepPacer:
    """How many fixed steps are due at a wall-clock instant.

    Sim time should advance `real_time_factor` times as fast as wall time.
    If the engine falls more than `max_lag` wall seconds behind, the backlog
    is dropped (the sim runs slower than asked; diagnostics show the real
    factor) rather than stepping in a burst to catch up.
    """

    def __init__(self, dt, real_time_factor, max_lag=0.25):
        self.dt = float(dt)
        self.real_time_factor = float(real_time_factor)
        self.max_lag = max_lag
        self._start = None
        self._taken = 0

    @property
    def unlimited(self):
        return self.real_time_factor <= 0.0

    def restart(self, now):
        self._start = now
        self._taken = 0

    def due(self, now):
        """Steps due at `now` (wall seconds); None means as many as possible."""
        if self.unlimited:
            return None
        if self._start is None:
            self.restart(now)
        elapsed = now - self._start
        due = math.floor(elapsed * self.real_time_factor / self.dt + 1e-9) - self._taken
        if due * self.dt / self.real_time_factor > self.max_lag:
            self.restart(now - self.dt / self.real_time_factor)
            due = 1
        return max(due, 0)

    def took(self, steps):
        self._taken += steps

    def tick_period(self):
        """Timer period for the node: one step's wall time, kept between
        MIN_TICK_S and 20 ms (command latency). Each tick costs about 0.1 ms
        of executor time whatever it runs, so at 1 kHz two steps share a
        tick: 5 % of the wall time instead of 10 %, commands wait at most
        2 ms, and every step is still published.
        At real_time_factor 0, FREE_RUN_CHECK_S."""
        if self.unlimited:
            return FREE_RUN_CHECK_S
        return min(max(self.dt / self.real_time_factor, MIN_TICK_S), 0.02)
