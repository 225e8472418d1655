"""`python -m benchmarks` is `physics-bench`."""
import sys

from .cli import main

sys.exit(main())
