"""The kernel cache directory: keyed by the package sources, old versions pruned."""
import os

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
    # the study holds no kernels: nothing it defines is compiled
    study = _config.Path(_config.__file__).parent / "study"
    assert all("njit" not in p.read_text() for p in study.rglob("*.py"))


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
