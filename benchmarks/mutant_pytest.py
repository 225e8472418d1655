"""`python -m benchmarks.mutant_pytest ORIGINAL COPY PYTEST-ARGS...`: pytest in
a copy of the repository that reads the original checkout's Numba cache.

Numba files each source file's kernels under a folder named by a hash of the
file's directory path, so a copy at another path would find none of the
original's kernels and compile everything (minutes). Here a file of the copy
is filed under its original's folder; an entry is still used only if the
copy's file has the same content (Numba checks a hash of the source), and
benchmarks/mutations.py removes, before each run, the entries of the mutated
file and of every file that imports it (their compiled code has the
unmutated callee built in).
"""
import os
import sys


def alias(original, copy):
    from numba.core import caching

    original, copy = os.path.abspath(original), os.path.abspath(copy)
    plain = caching._CacheLocator.get_suitable_cache_subpath.__func__

    def subpath(cls, py_file):
        path = os.path.abspath(py_file)
        if path == copy or path.startswith(copy + os.sep):
            path = original + path[len(copy):]
        return plain(cls, path)

    caching._CacheLocator.get_suitable_cache_subpath = classmethod(subpath)


def main(argv):
    original, copy, *args = argv
    alias(original, copy)
    import pytest

    return pytest.main(args)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
