"""Keep freed memory in the process for the next step's arrays (glibc).

A step of a large contact scene allocates and frees the same few hundred
kilobytes of numpy arrays every substep. With glibc's defaults, blocks
that large come from mmap (or from the top of the heap, trimmed back to the
system as soon as it is free), so every step pays for them again in page
faults: about 400 per step, a fifth of the step time, for 1,000 resting
spheres. Raising the mmap and trim thresholds keeps that memory in the
process once it has been used, at the cost of a resident size that stays
at its high-water mark (bounded by the thresholds below).

Process-wide, so it is done once, and only by scenes with contacts (the
ones whose steps allocate such arrays). Elsewhere (another C library, not
Linux) it does nothing.
"""
import ctypes
import sys

M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
MMAP_THRESHOLD = 32 << 20     # bytes; glibc's largest allowed value on 64-bit
TRIM_THRESHOLD = 64 << 20     # bytes of free heap top kept before returning it

_done = None


def keep_freed_memory() -> bool:
    """Set the thresholds (once per process). True when they were set."""
    global _done
    if _done is None:
        _done = False
        if sys.platform.startswith("linux"):
            try:
                libc = ctypes.CDLL("libc.so.6")
                _done = bool(libc.mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)
                             and libc.mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD))
            except (OSError, AttributeError):
                _done = False
    return _done
