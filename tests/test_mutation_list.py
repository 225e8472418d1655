"""The mutation check's own pieces (the run itself is `physics-bench
mutations`, not part of `make test`): every mutation still applies to the
source as it is, they span every stage, and a mutant's Numba cache loses
exactly the kernels that can reach the changed line."""
import os

import pytest

from benchmarks import mutations
from benchmarks.mutation_list import MUTATIONS

STAGES = {"integrate", "forces", "detect", "rows", "solve", "restitution", "correct", "ccd", "sleep", "events"}


@pytest.mark.parametrize("mutation", MUTATIONS, ids=lambda m: m.name)
def test_mutation_applies_to_the_current_source(mutation):
    """A failure here means the line changed: update the mutation in
    benchmarks/mutation_list.py to the new line, so the check keeps planting it."""
    assert mutations.check(mutation) is None
    for test in mutation.tests:
        assert os.path.isfile(os.path.join(mutations.REPO, test)), test


def test_at_least_thirty_mutations_over_every_stage():
    assert len(MUTATIONS) >= 30
    assert {m.stage for m in MUTATIONS} == STAGES
    assert len({m.name for m in MUTATIONS}) == len(MUTATIONS)


def test_a_mutant_recompiles_the_mutated_file_and_every_importer_only(tmp_path):
    for name, text in {"leaf.py": "X = 1\n", "mid.py": "from leaf import X\n", "top.py": "import mid\n",
                       "other.py": "import json\n", "pkg/__init__.py": "from .inner import Y\n",
                       "pkg/inner.py": "from ..leaf import X as Y\n"}.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    got = {os.path.relpath(p, tmp_path) for p in mutations.dependents(str(tmp_path), str(tmp_path / "leaf.py"))}
    assert got == {"leaf.py", "mid.py", "top.py", "pkg/inner.py", "pkg/__init__.py"}

    cache = tmp_path / "cache"
    folder = cache / mutations._cache_folder(str(tmp_path / "leaf.py"))
    folder.mkdir(parents=True)
    for f in ("leaf.f-3.py311.nbi", "leaf.f-3.py311.1.nbc", "leafy.g-1.py311.nbi", "other.h-2.py311.nbi"):
        (folder / f).write_text("")
    assert mutations.prune_cache(str(cache), [str(tmp_path / "leaf.py")]) == 2
    assert sorted(os.listdir(folder)) == ["leafy.g-1.py311.nbi", "other.h-2.py311.nbi"]


def test_a_copy_reads_the_original_checkouts_cache_folders(tmp_path):
    from numba.core import caching

    from benchmarks import mutant_pytest

    original, copy = tmp_path / "orig", tmp_path / "copy"
    saved = vars(caching._CacheLocator)["get_suitable_cache_subpath"]
    plain = caching._CacheLocator.get_suitable_cache_subpath
    try:
        mutant_pytest.alias(str(original), str(copy))
        aliased = caching._CacheLocator.get_suitable_cache_subpath
        assert aliased(str(copy / "physics_core" / "x.py")) == plain(str(original / "physics_core" / "x.py"))
        assert aliased(str(tmp_path / "elsewhere" / "x.py")) == plain(str(tmp_path / "elsewhere" / "x.py"))
        assert aliased(str(copy / "x.py")) == mutations._cache_folder(str(original / "x.py"))
    finally:
        caching._CacheLocator.get_suitable_cache_subpath = saved
