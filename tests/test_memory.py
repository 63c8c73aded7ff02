"""Carved blocks and their reuse (mortar1d3d._memory)."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import _memory

BIG = (((700, 600), np.float64), (5000, np.int32))     # > 2 MiB: pooled


@pytest.fixture
def empty_pool():
    _memory.release_pool()
    yield
    _memory.release_pool()


def test_a_dropped_block_serves_the_next_carve(empty_pool):
    a, b = _memory.carve(*BIG)
    address = a.ctypes.data
    assert a.shape == (700, 600) and b.dtype == np.int32 and a.ctypes.data % (2 << 20) == 0
    del a, b
    c, d = _memory.carve(*BIG)
    assert c.ctypes.data == address
    assert len(_memory._pool) == 1


def test_a_block_with_any_array_alive_is_not_reused(empty_pool):
    a, b = _memory.carve(*BIG)
    address = a.ctypes.data
    piece = a[3, 10:20]             # derived from a carved array: refers to the block
    piece[:] = 7.0
    del a, b
    c, d = _memory.carve(*BIG)
    c[:] = 1.0
    assert c.ctypes.data != address
    assert np.all(piece == 7.0)
    del piece, c, d
    e, f = _memory.carve(*BIG)
    assert e.ctypes.data == address        # both blocks free and equal: the older one is taken


def test_a_new_block_first_gives_back_unused_blocks_of_its_size(empty_pool, monkeypatch):
    monkeypatch.setattr(_memory, "POOL_LIMIT", 10 << 20)
    held = [_memory.carve(((n, 1000), np.float64)) for n in (400, 500, 600)]   # blocks of 6, 6, 8 MiB
    assert [block.nbytes >> 20 for block in _memory._pool] == [6, 6, 8]
    del held
    _memory.carve(((1200, 1000), np.float64))        # fits none (12 MiB): unused ones of 12 MiB go, oldest first
    assert [block.nbytes >> 20 for block in _memory._pool] == [8, 12]


def test_blocks_in_use_at_once_are_kept_beyond_the_limit(empty_pool, monkeypatch):
    """Unused blocks are kept up to the most the pool had in use at once (20 MiB here), not only up to
    POOL_LIMIT: a repeated call of any size finds all its blocks again."""
    monkeypatch.setattr(_memory, "POOL_LIMIT", 10 << 20)
    sizes = (400, 500, 600)                                                    # blocks of 6, 6, 8 MiB
    held = [_memory.carve(((n, 1000), np.float64))[0] for n in sizes]
    addresses = [a.ctypes.data for a in held]
    assert _memory.pool_bytes() == (20 << 20, 0)
    del held
    assert _memory.pool_bytes() == (0, 20 << 20)
    again = [_memory.carve(((n, 1000), np.float64))[0] for n in sizes]
    assert [a.ctypes.data for a in again] == addresses
    del again
    _memory.release_pool()
    assert _memory.pool_bytes() == (0, 0) and _memory._most_in_use == 0


def test_reused_memory_changes_no_result(empty_pool, monkeypatch):
    """Every carved array is written before it is read: garbage in reused blocks changes no bit."""
    beams, solid = m13.generate.fibre_cube(4, 12, 5, curved=True)
    solid = m13.generate.distort(solid, 0.1, seed=3)
    reference = {}
    for integration in ("element", "segment", "auto"):
        ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=3, lm="line3")
        reference[integration] = (ops.D.toarray(), ops.M.toarray(), ops.kappa.copy(), ops.points.copy())
    monkeypatch.setattr(_memory, "_HUGE_PAGE", 4096)   # pool every carve, however small
    real_block = _memory._block

    def poisoned(n_bytes):
        block = real_block(n_bytes)
        block[:] = 0xFF
        return block
    monkeypatch.setattr(_memory, "_block", poisoned)
    for _ in range(2):
        for integration, (D, M, kappa, points) in reference.items():
            ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=3, lm="line3")
            assert np.array_equal(ops.D.toarray(), D) and np.array_equal(ops.M.toarray(), M)
            assert np.array_equal(ops.kappa, kappa) and np.array_equal(ops.points, points)
    assert len(_memory._pool) > 0


def test_a_zero_limit_turns_reuse_off(empty_pool, monkeypatch):
    monkeypatch.setattr(_memory, "POOL_LIMIT", 0)
    a, b = _memory.carve(*BIG)
    assert a.shape == (700, 600) and a.ctypes.data % (2 << 20) == 0
    del a, b
    _memory.carve(*BIG)
    assert _memory._pool == []
