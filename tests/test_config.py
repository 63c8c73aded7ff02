"""The kernel cache directory: keyed by the package sources, old versions pruned."""
import os
import re

from mortar1d3d import _config


def test_cache_directory_is_keyed_by_the_sources(tmp_path):
    assert _config.CACHE_DIR.name == f"mortar1d3d-{_config._source_fingerprint()}"
    # an edit of any module, even one no cached kernel lives in, gives a new key; the same text the same
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    (tmp_path / "notes.txt").write_text("not a source")
    before = _config._source_fingerprint(tmp_path)
    assert len(before) == 16 and before == _config._source_fingerprint(tmp_path)
    (tmp_path / "notes.txt").write_text("edited, still not a source")
    assert _config._source_fingerprint(tmp_path) == before
    (tmp_path / "sub" / "b.py").write_text("y = 3\n")
    edited = _config._source_fingerprint(tmp_path)
    assert edited != before
    (tmp_path / "sub" / "b.py").rename(tmp_path / "b.py")               # same text, other file: new key
    assert _config._source_fingerprint(tmp_path) not in (before, edited)


def test_kernel_free_subpackages_do_not_change_the_key(tmp_path):
    (tmp_path / "study").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "study" / "report.py").write_text("text = 'one'\n")
    before = _config._source_fingerprint(tmp_path)
    (tmp_path / "study" / "report.py").write_text("text = 'two'\n")
    assert _config._source_fingerprint(tmp_path) == before
    assert _config._source_fingerprint(tmp_path, skip=()) != _config._source_fingerprint(tmp_path)
    # the kernel-free subpackages hold no kernels: nothing they define is compiled, and no kernel
    # module imports from them (a table frozen into a kernel would then escape the key)
    package = _config.Path(_config.__file__).parent
    assert set(_config.KERNEL_FREE) >= {"study", "distributed", "model"}
    for name in _config.KERNEL_FREE:
        for p in (package / name).rglob("*.py"):
            text = p.read_text()
            assert not re.search(r"njit|@\s*(numba\.)?(jit|vectorize|guvectorize|cfunc)\b|prange", text), p
    kernel_modules = [p for p in package.rglob("*.py") if p.relative_to(package).parts[0] not in _config.KERNEL_FREE
                      and "njit" in p.read_text()]
    assert len(kernel_modules) > 20
    for p in kernel_modules:
        for name in _config.KERNEL_FREE:
            assert f"from ..{name}" not in p.read_text() and f"from .{name}" not in p.read_text() \
                and f"mortar1d3d.{name}" not in p.read_text(), (p, name)


def test_prune_keeps_the_newest_other_versions(tmp_path):
    current = tmp_path / "mortar1d3d-0000000000000000"
    current.mkdir()
    os.utime(current, (1.0, 1.0))                          # the current one stays, however old
    others = [tmp_path / f"mortar1d3d-{k:016x}" for k in range(1, 7)]
    for age, d in enumerate(others):                       # others[0] newest
        (d / "sub").mkdir(parents=True)
        (d / "sub" / "kernel.nbi").write_bytes(b"x")
        os.utime(d, (1e9 - age, 1e9 - age))
    unrelated = [tmp_path / "mortar1d3d-notes", tmp_path / "numba-cache"]
    for d in unrelated:
        d.mkdir()
    (tmp_path / "mortar1d3d-000000000000000f").write_text("a file, not a cache")
    _config._prune_caches(current, keep=3)
    left = sorted(p.name for p in tmp_path.iterdir())
    expected = sorted([current.name] + [d.name for d in others[:3]] + [d.name for d in unrelated]
                      + ["mortar1d3d-000000000000000f"])
    assert left == expected
