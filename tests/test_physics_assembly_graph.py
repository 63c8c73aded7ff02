"""The assembly graph of the solid (physics/assembly_graph.py): CSR pattern, slots and colouring."""
import numpy as np
import pytest
import scipy.sparse as sp

import mortar1d3d as m13
from mortar1d3d.elements.solid.dispatch import N_NODES
from mortar1d3d.physics.assembly_graph import assembly_graph


def mixed_mesh():
    """Hexahedra, tetra10 and hexahedron27 side by side (a mesh with several node counts)."""
    parts = [m13.generate.box((0, 0, 0), (1, 1, 1), (3, 2, 2), "hexahedron"),
             m13.generate.box((1, 0, 0), (2, 1, 1), (1, 1, 1), "tetra10"),
             m13.generate.box((0, 1, 0), (1, 2, 1), (2, 1, 1), "hexahedron27")]
    offsets = np.cumsum([0] + [p.n_nodes for p in parts])
    return m13.SolidMesh(np.vstack([p.points for p in parts]),
                         {p.blocks[0][0].name: p.blocks[0][1] + o for p, o in zip(parts, offsets)})


def element_nodes(mesh):
    codes = np.asarray(mesh.element_codes, dtype=np.int64)
    return [mesh.connectivity[e, : N_NODES[c]] for e, c in enumerate(codes)]


@pytest.mark.parametrize("block", [1, 2, 5, 64])
def test_colours_share_no_node_and_cover_every_block_once(block):
    mesh = mixed_mesh()
    nodes = element_nodes(mesh)
    g = assembly_graph(np.ascontiguousarray(mesh.connectivity, dtype=np.int64),
                       np.ascontiguousarray(mesh.element_codes, dtype=np.int64), mesh.n_nodes, block)
    n_blocks = -(-mesh.n_elements // block)
    assert np.array_equal(np.sort(g.colour_blocks), np.arange(n_blocks))
    for c in range(len(g.colour_ptr) - 1):
        members = g.colour_blocks[g.colour_ptr[c]:g.colour_ptr[c + 1]]
        assert np.all(np.diff(members) > 0)
        seen = set()
        for k in members:
            block_nodes = set(np.concatenate(nodes[k * block:(k + 1) * block]).tolist())
            assert not (seen & block_nodes), (c, k)
            seen |= block_nodes
    if block == 1:
        assert len(g.colour_ptr) - 1 > 1


def test_pattern_and_slots_match_the_element_node_pairs():
    mesh = mixed_mesh()
    nodes = element_nodes(mesh)
    g = assembly_graph(np.ascontiguousarray(mesh.connectivity, dtype=np.int64),
                       np.ascontiguousarray(mesh.element_codes, dtype=np.int64), mesh.n_nodes, 4)
    rows = np.concatenate([np.repeat(n, len(n)) for n in nodes])
    cols = np.concatenate([np.tile(n, len(n)) for n in nodes])
    graph = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(mesh.n_nodes, mesh.n_nodes))
    graph.sum_duplicates()
    graph.sort_indices()
    assert np.array_equal(g.node_ptr, graph.indptr) and np.array_equal(g.neighbours, graph.indices)
    expanded = sp.kron(graph, np.ones((3, 3)), format="csr")
    expanded.sort_indices()
    assert np.array_equal(g.indptr, expanded.indptr) and np.array_equal(g.indices, expanded.indices)
    for e, n in enumerate(nodes):
        slots = g.slots[g.slot_ptr[e]:g.slot_ptr[e + 1]].reshape(len(n), len(n))
        for a, v in enumerate(n):
            assert np.array_equal(g.neighbours[g.node_ptr[v] + slots[a]], n)
