"""A progress line on stderr: runs done of the total, failures, rate and time left.

On a terminal it is redrawn in place at most 5 times a second; otherwise
(a log file, CI) one line is printed every `every` seconds and at the end.
"""
import sys
import time


def _clock(seconds):
    if seconds != seconds or seconds == float("inf"):
        return "--:--"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


class Progress:
    def __init__(self, total, *, already=0, failed=0, stream=None, every=10.0, enabled=True, width=24):
        self.total, self.done, self.failed = total, already, failed
        self.already = already          # rows found in the file when resuming: not in the rate
        self.stream = stream or sys.stderr
        self.tty = enabled and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.enabled, self.every, self.width = enabled, every, width
        self.start = time.monotonic()
        self._last = 0.0

    def update(self, done, failed):
        self.done += done
        self.failed += failed
        now = time.monotonic()
        if self.enabled and now - self._last >= (0.2 if self.tty else self.every):
            self._last = now
            self._write(self.line())

    def line(self):
        elapsed = time.monotonic() - self.start
        new = self.done - self.already
        rate = new / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else float("nan")
        frac = self.done / self.total if self.total else 1.0
        bar = "#" * int(frac * self.width)
        return (f"[{bar:<{self.width}}] {self.done}/{self.total} runs, {self.failed} failed, "
                f"{rate:.1f} runs/s, {_clock(elapsed)} elapsed, {_clock(left)} left")

    def _write(self, text):
        self.stream.write(("\r" + text + "\x1b[K") if self.tty else text + "\n")
        self.stream.flush()

    def finish(self):
        if self.enabled:
            self._write(self.line())
            if self.tty:
                self.stream.write("\n")
            self.stream.flush()
