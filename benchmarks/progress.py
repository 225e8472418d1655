"""Progress lines on stderr, so a long study shows where it is and the tables stay on disk."""
import sys
from time import perf_counter


class Progress:
    """`[label 3/40] message  (12 s, ~2 min left)`; the estimate assumes equal items."""

    def __init__(self, label, total, stream=None):
        self.label, self.total, self.done = label, max(1, int(total)), 0
        self.stream = stream or sys.stderr
        self.start = perf_counter()

    def step(self, message):
        self.done += 1
        elapsed = perf_counter() - self.start
        left = elapsed / self.done * (self.total - self.done)
        eta = f", ~{_duration(left)} left" if self.done < self.total else ""
        self.stream.write(f"[{self.label} {self.done}/{self.total}] {message}  "
                          f"({_duration(elapsed)}{eta})\n")
        self.stream.flush()

    def note(self, message):
        self.stream.write(f"[{self.label}] {message}\n")
        self.stream.flush()


def _duration(s):
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.1f} min"
