"""What /diagnostics reports, gathered over the window since the last report."""

import time

from msg_adapters.diagnostics import ERROR, OK, WARN, diagnostic_array

STATUS_NAME = "physics: simulation"


class DiagnosticsWindow:
    def __init__(self, world, drop_reasons):
        self.world = world
        self.dropped_total = {reason: 0 for reason in drop_reasons}
        self.applied_total = 0
        self.received_total = 0  # commands that reached a command callback
        self._open(time.monotonic())

    def _open(self, now):
        self._wall_start = now
        self._sim_start = self.world.time
        self._steps = 0
        self._loop_seconds = 0.0
        self._engine_seconds = 0.0
        self._dropped = 0
        self._profile_start = dict(getattr(self.world, "profile", {}) or {})
        self._integration_start = dict(getattr(self.world, "integration_stats", {}) or {})
        self._smallest_step = float("inf")
        self._max_local_error = 0.0

    def stepped(self, applied, loop_seconds):
        self._steps += 1
        self._loop_seconds += loop_seconds
        self._engine_seconds += float(getattr(self.world, "last_step_seconds", 0.0))
        self.applied_total += applied
        last = getattr(self.world, "last_step_integration_stats", None)
        if last:
            self._smallest_step = min(self._smallest_step, last["smallest_step_s"] or float("inf"))
            self._max_local_error = max(self._max_local_error, last["max_local_error"])

    def dropped(self, reason):
        self.dropped_total[reason] = self.dropped_total.get(reason, 0) + 1
        self._dropped += 1

    def report(
        self,
        stamp_ns,
        hardware_id,
        paused,
        target_rtf,
        recording,
        fault="",
        recording_error="",
        isolated=(),
        queued=0,
        unknown_topics=(0, 0),
        body_topics=(0, 0),
    ):
        """DiagnosticArray for the window just ended; opens the next one."""
        now = time.monotonic()
        w = self.world
        wall = max(now - self._wall_start, 1e-9)
        # A reset moves sim time backwards; the window then measures from 0.
        sim = w.time - self._sim_start if w.time >= self._sim_start else w.time
        steps = max(self._steps, 1)
        values = {
            "sim_time_s": float(w.time),
            "steps": int(w.step_index),
            "real_time_factor": sim / wall,
            "real_time_factor_target": float(target_rtf),
            "step_time_ms": 1e3 * self._engine_seconds / steps,
            "loop_time_ms": 1e3 * self._loop_seconds / steps,
            "bodies": len(w.model.names),
            "contacts": len(w.contacts),
            "dropped_commands": sum(self.dropped_total.values()),
        }
        for reason, count in self.dropped_total.items():
            values[f"dropped_{reason}"] = count
        values["applied_commands"] = self.applied_total
        # applied + dropped + queued = received (the unknown-body topics' drops included)
        values["received_commands"] = self.received_total + self.dropped_total.get("unknown_body", 0)
        values["queued_commands"] = int(queued)
        values["unknown_body_topics"] = int(unknown_topics[0])
        values["unknown_body_topics_ignored"] = int(unknown_topics[1])
        # per-body endpoints made, and topics a large world makes when a peer uses them (body_topics.py)
        values["body_topics"] = int(body_topics[0])
        values["body_topics_on_demand"] = int(body_topics[1])
        values["isolated_bodies"] = ", ".join(isolated)
        values["paused"] = bool(paused)
        values["recording"] = recording
        values["recording_error"] = recording_error
        profile = dict(getattr(w, "profile", {}) or {})
        for stage, seconds in profile.items():
            spent = seconds - self._profile_start.get(stage, 0.0)
            values[f"stage_{stage}_ms"] = 1e3 * max(spent, 0.0) / steps
        missed = self._integration_values(values, steps)
        if fault:
            level, message = ERROR, f"stopped: {fault}"
        elif recording_error:
            level, message = ERROR, recording_error
        elif isolated:
            level, message = WARN, f"{len(isolated)} bodies frozen after a non-finite state: {', '.join(isolated[:10])}"
        elif missed:
            level, message = WARN, (f"{missed} internal steps at accuracy.min_step above the requested "
                                    "accuracy in the last window")
        elif self._dropped:
            level, message = WARN, f"{self._dropped} bad commands dropped in the last {wall:.1f} s"
        else:
            level, message = OK, "paused" if paused else "running"
        self._open(now)
        return diagnostic_array(stamp_ns, STATUS_NAME, hardware_id, level, message, values)

    def _integration_values(self, values, steps):
        """`integrator: adaptive`'s statistics (World.integration_stats) into
        values: per step over the window, the window's extremes, the totals;
        returns the window's steps forced at min_step."""
        total = dict(getattr(self.world, "integration_stats", {}) or {})
        if not total:
            return 0
        start = self._integration_start
        for name in ("internal_steps", "rejected_steps", "force_evaluations"):
            values[f"integration_{name}_per_step"] = (total[name] - start.get(name, 0)) / steps
            values[f"integration_{name}_total"] = total[name]
        values["integration_smallest_step_s"] = self._smallest_step if self._smallest_step < float("inf") else 0.0
        values["integration_max_local_error"] = self._max_local_error
        values["integration_steps_at_min_step_total"] = total["steps_at_min_step"]
        return total["steps_at_min_step"] - start.get("steps_at_min_step", 0)
