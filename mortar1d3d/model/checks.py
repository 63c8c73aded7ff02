"""Checks of a prepared model before (and after) its solve: supports, mechanisms, small strain.

* :func:`check_supports`: every body (the solid with the beams coupled to it, each uncoupled
  beam) is held against every rigid-body motion, or a SceneError names the free motions
  (:func:`free_rigid_motions`);
* :func:`check_zero_energy_modes`: no beam can move without stiffness against it once every body
  is held (a truss between supports, an uncoupled beam end);
* :func:`check_linear_displacements`: a linear result whose displacements are not small against
  the body gets a LargeDeformationWarning.

Each takes the :class:`~mortar1d3d.model.Model` and uses its DOF map, supports and
``rigid_body_modes``.
"""
import warnings

import numpy as np
import scipy.sparse as sp

from ..errors import LargeDeformationWarning, format_ids
from ..scene import SceneError

LINEAR_DISPLACEMENT_LIMIT = 0.1  # max |u| / body size above which a linear result is flagged (LargeDeformationWarning)


def free_rigid_motions(R, Rf, tol, centre, size):
    """Names of a basis of the rigid-body motions of a body that its supports do not stop.

    Parameters
    ----------
    R : (m, 6) float
        The body's rigid-body modes (:meth:`Model.rigid_body_modes` restricted to its DOFs):
        translations in x, y, z, then rotations about x, y, z through ``centre`` with the
        positions scaled by ``1/size``.
    Rf : (k, 6) float
        The rows of ``R`` at fixed DOFs.
    tol : float
        Singular values up to ``tol`` count as zero (the rank threshold of the caller).
    centre : (3,) float
    size : float

    Returns
    -------
    list of str
        One name per free motion, ``rank(R) − rank(Rf)`` of them: the free motions are ``R a``
        with ``Rf a = 0``, counted modulo the coefficients ``a`` that move nothing (``R a = 0``,
        e.g. a straight torsion-free beam turning about its own axis). The basis is the reduced
        row echelon form with rotations first: a single-axis motion gets its plain name ("rotation
        about x"), any other an axis direction and, when it does not pass through the centroid,
        a point on it.
    """
    _, s, Vt = np.linalg.svd(R)
    row = Vt[: np.count_nonzero(s > tol)]                   # coefficients that move the body
    if len(Rf):
        _, sf, Vft = np.linalg.svd(Rf)
        null = Vft[np.count_nonzero(sf > tol):]             # coefficients the supports do not see
    else:
        null = np.eye(6)
    # null(Rf) is the orthogonal sum of null(R) and null(Rf) ∩ row(R): projecting it onto row(R)
    # leaves the free motions, with singular values 1 (kept) or 0 (motions that move nothing)
    _, sp_, basis = np.linalg.svd(null @ row.T @ row)
    basis = basis[: np.count_nonzero(sp_ > 0.5)]
    order = [3, 4, 5, 0, 1, 2]                              # rotations first: pivots on rotations
    A = basis[:, order]
    r = 0
    for c in range(6):
        if r == len(A):
            break
        p = r + int(np.argmax(np.abs(A[r:, c])))
        if abs(A[p, c]) <= 1e-8:                             # rows are orthonormal: O(1) entries
            continue
        A[[r, p]] = A[[p, r]]
        A[r] /= A[r, c]
        others = np.arange(len(A)) != r
        A[others] -= np.outer(A[others, c], A[r])
        r += 1
    coefficients = np.empty_like(A)
    coefficients[:, order] = A
    names = [_motion_name(a[:3], a[3:] / size, centre, size) for a in coefficients]
    return sorted(names, key=lambda name: not name.startswith("translation"))


def _motion_name(v, w, centre, size):
    """Name of the rigid motion ``u(X) = v + w × (X − centre)``."""
    def direction(d):
        d = d / np.linalg.norm(d)
        d = np.where(np.abs(d) <= 1e-9, 0.0, d)
        d = d if d[np.flatnonzero(d)[0]] > 0 else -d            # a motion's sign is arbitrary
        nonzero = np.flatnonzero(d)
        if len(nonzero) == 1:
            return "xyz"[nonzero[0]]
        return "(" + ", ".join(f"{x:.3g}" for x in d + 0.0) + ")"

    wn, vn = float(np.linalg.norm(w)), float(np.linalg.norm(v))
    if wn * size <= 1e-9 * vn:
        d = direction(v)
        return f"translation {'in' if len(d) == 1 else 'along'} {d}"
    axis = w / wn
    name = f"rotation about {direction(w)}"
    offset = np.cross(w, v) / wn ** 2                          # centroid → nearest point of the axis
    if np.linalg.norm(offset) > 1e-9 * size:
        point = centre + offset
        # round-off of the coordinates (scale: size and distance from the origin) printed as 0
        point[np.abs(point) <= 1e-9 * (size + np.abs(centre).max())] = 0.0
        name += " through (" + ", ".join(f"{x:.4g}" for x in point + 0.0) + ")"
    slide = float(v @ axis) / wn                                # translation along the axis per radian
    if abs(slide) > 1e-9 * size:
        name += f" with a slide of {slide:.3g} along it per radian (screw)"
    return name


def bodies(model):
    """Groups of displacement DOFs that move together (solid + coupled beams; free beams alone)."""
    bodies = []
    solid_body = [np.arange(3 * model.n_solid_nodes)] if model.solid_mesh is not None else []
    for g in model.groups:
        coupled_elements = (np.unique(g.operators.point_fields["beam_element"]) if g.operators is not None
                            else np.zeros(0, np.int64))
        for k, entry in enumerate(g.entries):
            a, b = g.entry_elements[k]
            nodes = np.unique(g.mesh.elements[a:b])
            dofs = g.dofs.dofs(nodes, np.arange(g.dofs.dofs_per_node))
            if g.rotations.size:
                dofs = np.concatenate([dofs, g.rotations.dofs(np.unique(g.type.rotation_nodes(g.mesh)[a:b]),
                                                              [0, 1, 2])])
            inside = np.any((coupled_elements >= a) & (coupled_elements < b))
            if inside:
                solid_body.append(dofs)
            else:
                bodies.append((f"beam {entry}" + (" (outside the solid, so not coupled)"
                                                  if model.solid_mesh is not None else ""), dofs))
    if solid_body:
        label = "the solid" + (" with its coupled beams" if len(solid_body) > 1 else "")
        bodies.insert(0, (label, np.concatenate(solid_body)))
    return bodies


def check_supports(model):
    """Raise SceneError if a body can move as a rigid body (before any solve)."""
    model.counts["check.rigid_body_modes"] += 1
    fixed = np.zeros(model.n_displacement_dofs, dtype=bool)
    fixed[model.fixed_dofs[model.fixed_dofs < model.n_displacement_dofs]] = True
    for label, dofs in bodies(model):
        R = model.rigid_body_modes(dofs)[dofs]
        s_all = np.linalg.svd(R, compute_uv=False)
        rank_all = int(np.count_nonzero(s_all > 1e-10 * s_all[0]))
        Rf = R[fixed[dofs]]
        if len(Rf):
            s_fix = np.linalg.svd(Rf, compute_uv=False)
            rank_fix = int(np.count_nonzero(s_fix > 1e-10 * s_all[0]))
        else:
            rank_fix = 0
        if rank_fix < rank_all:
            centre, size = model._mode_frame(dofs, ~model._position_triplets())
            free = free_rigid_motions(R, Rf, 1e-10 * s_all[0], centre, size)
            raise SceneError(f"dirichlet: {label} can move freely ({len(free)} rigid-body mode(s) not "
                             f"fixed: {', '.join(free)}); add supports ([[dirichlet]]) that stop these motions")
    check_zero_energy_modes(model)


def check_linear_displacements(model, z, stacklevel=3):
    """Warn (LargeDeformationWarning) for each body that the linear solution ``z`` (unknowns)
    moves by more than LINEAR_DISPLACEMENT_LIMIT of its size, the diagonal of its bounding box:
    linear kinematics assumes displacements small against the body."""
    u = model.basis.to_physical(z[: model.n_displacement_dofs]).reshape(-1, 3)
    X = model.reference().reshape(-1, 3)
    position = model._position_triplets()
    for label, dofs in bodies(model):
        triplets = np.unique(dofs // 3)
        triplets = triplets[position[triplets]]
        size = float(np.linalg.norm(np.ptp(X[triplets], axis=0)))
        umax = float(np.linalg.norm(u[triplets], axis=1).max())
        if umax > LINEAR_DISPLACEMENT_LIMIT * size:
            warnings.warn(f"analysis.kinematics: {label} moves by up to {umax:.3g}, {umax / size:.3g} times its "
                          f"size {size:.3g} (the diagonal of its bounding box); with displacements that large, "
                          "linear kinematics does not hold. Check the units (E in Pa, not MPa, for a scene in "
                          "metres and newtons) or use kinematics = \"nonlinear\"", LargeDeformationWarning,
                          stacklevel=stacklevel)


def check_zero_energy_modes(model):
    """Raise SceneError if a beam has a zero-energy mode other than a rigid-body motion.

    Runs after the rigid-body check (so every body is held against rigid motion): each chain
    of beam elements is probed with the solid held, on its free DOFs, for motions that
    neither the beam stiffness at the reference state nor the coupling resists
    (:func:`~mortar1d3d.mechanisms.find_mechanisms`). The modes found are kept in
    ``zero_energy_modes`` (list of ``(group, Mechanism)``) before the error is raised.
    """
    from ..mechanisms import chains, find_mechanisms
    model.zero_energy_modes = []
    if not model.groups:
        return
    model.counts["check.zero_energy_modes"] += 1
    fixed = np.zeros(model.n_displacement_dofs, dtype=bool)
    fixed[model.fixed_dofs[model.fixed_dofs < model.n_displacement_dofs]] = True
    # a clamped tangent is fixed in its rotated frame (direction, not length): the probe works on
    # physical components and holds the whole tangent there, which hides no mechanism (changing the
    # tangent's length alone stretches the element)
    for first in model.basis.starts:
        fixed[first: first + 3] = fixed[first: first + 3].any()
    for g in model.groups:
        rows = None
        if g.operators is not None:
            if model.scene.coupling["constraint"] == "gauss_point":
                rows = g.coupling.G[:, g.dofs.slice]
            else:
                rows = g.operators.D.tocsr()[g.coupling.coupled_rows]
        if g.rotations.size:
            if g.rotational is not None:
                # the rotational coupling's rows act on the spins (after the centreline DOFs)
                rows = _with_spin_rows(rows, g.rotational.beam_rows(), g.mesh.n_centreline_dofs)
            found = find_mechanisms(g.mesh, rows, np.concatenate([fixed[g.dofs.slice], fixed[g.rotations.slice]]),
                                    rotation_nodes=g.type.rotation_nodes(g.mesh))
        else:
            found = find_mechanisms(g.mesh, rows, fixed[g.dofs.slice])
        model.zero_energy_modes += [(g, m) for m in found]
    if model.zero_energy_modes:
        g, m = model.zero_energy_modes[0]
        more = len(model.zero_energy_modes) - 1
        raise SceneError(mechanism_message(model, g, m, chains(g.mesh)[1])
                         + (f" ({more} more chain(s) of beam elements have such modes)" if more else ""))


def _with_spin_rows(rows, spin_rows, n_centreline):
    """Coupling rows over ``[centreline | spins]``: the positional rows (centreline columns, or
    None) stacked on the rotational coupling's rows (spin columns)."""
    spin = sp.hstack([sp.csr_matrix((spin_rows.shape[0], n_centreline)), spin_rows], format="csr")
    if rows is None:
        return spin
    rows = sp.csr_matrix(rows)
    rows = sp.hstack([rows, sp.csr_matrix((rows.shape[0], spin_rows.shape[1]))], format="csr")
    return sp.vstack([rows, spin], format="csr")


def mechanism_message(model, g, m, label):
    """The SceneError text of one zero-energy mode: which beam, which nodes, why, what to do."""
    k = int(np.searchsorted(g.node_offsets, m.nodes[0], side="right")) - 1
    entry, first = g.entries[k], int(g.node_offsets[k])
    last = int(g.node_offsets[k + 1]) if k + 1 < len(g.node_offsets) else g.mesh.n_nodes
    entry_chains = np.unique(label[first:last])
    where = f"beams[{entry}]"
    if len(entry_chains) > 1:
        where += (f" (chain {int(np.searchsorted(entry_chains, m.chain))} of its {len(entry_chains)} "
                  f"unconnected chains, nodes {m.nodes[0] - first}..{m.nodes[-1] - first})")
    local = m.moving - first
    per_node = g.dofs.dofs_per_node
    node = int(m.moving[0])
    comps = np.abs(m.mode[per_node * node: per_node * node + 3])
    axis = "xyz"[int(np.argmax(comps))] if comps.max() > 0 else "its tangent"
    coupled = np.zeros(g.mesh.n_nodes, dtype=bool)
    if g.operators is not None:
        elements = np.unique(g.operators.point_fields["beam_element"])
        coupled[np.unique(g.mesh.elements[elements])] = True
    outside = ~coupled[m.moving]
    n_cl = g.mesh.n_centreline_dofs
    if g.rotations.size and np.abs(m.mode[:n_cl]).max() <= 1e-8 * np.abs(m.mode).max():
        # only the triads move: the cross-sections turn about a straight centreline
        entry_nodes = f"beam:{entry}:start"
        return (f"{where}: zero-energy mode (a mechanism: the beam can move without any stiffness against it, so "
                f"no solver can determine that motion): its cross-sections turn about the centreline (a twist "
                f"about its axis, nodes {format_ids(np.sort(local))}); the coupling ties the centreline only, not the "
                f"rotation of the cross-sections. Support the rotation at one node ([[dirichlet]] on = "
                f"\"{entry_nodes}\", rotation = [0, 0, 0]), or tie the cross-sections to the solid "
                "(coupling.rotational)")
    if outside.all() and model.solid_mesh is None:
        why = "nothing but the beam itself holds the moving nodes"
        advice = (f"a {g.model} has no bending stiffness, so between supports its nodes are held only along its bars: "
                  "support them sideways ([[dirichlet]] with components) or use model = \"torsion_free\" "
                  "(straight beams)" if not g.type.bending else "support the moving nodes ([[dirichlet]])")
    elif outside.all():
        why = "the moving nodes are not coupled to the solid (they lie outside it)"
        advice = (f"a {g.model} has no bending stiffness, so an uncoupled part of it is held only along its bars: "
                  "support these nodes ([[dirichlet]]), end the beam where it leaves the solid, or use "
                  "model = \"torsion_free\" (straight beams)" if not g.type.bending else
                  "support the moving nodes ([[dirichlet]])")
    else:
        why = "the coupling holds this beam at too few places"
        advice = ("couple more of it: integration = \"segment\" or more Gauss points (n_gauss) where a beam "
                  "element barely enters the solid, or support it ([[dirichlet]])")
    return (f"{where}: zero-energy mode (a mechanism: the beam can move without any stiffness against it, so "
            f"no solver can determine that motion): "
            + (f"nodes {format_ids(local)} move (largest: node {local[0]}, " if len(local) > 1 else
               f"node {local[0]} moves (")
            + f"{axis}); {why}. {advice[0].upper() + advice[1:]}")
