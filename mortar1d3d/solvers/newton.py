"""Newton–Raphson with load steps and automatic step cutting, and the one step of a linear analysis.

:func:`solve_load_steps` solves a nonlinear system, :func:`solve_linear_step` a linear one (one
exactly solved step, no Newton loop). The system is any object with

* ``fixed`` (int array): unknowns prescribed by Dirichlet conditions, ``free`` the others;
* ``prescribed(t)``: values of the fixed unknowns at load factor ``t``;
* ``residual(z, t, tangent=True)``: ``(r, K)``, the full residual vector (internal minus external
  forces, plus constraint rows if any) and its Jacobian (scipy sparse) or None;
* ``solve_linear(K_ff, b, z_f, rtol=...)``: solution of the reduced linear system to the relative
  residual ``rtol`` (or its round-off level); :func:`solve_linear_step` passes neither ``z_f`` nor
  ``rtol``: the system's own target for its one solve;

and optionally

* ``update(z, free, dz)``: apply the Newton increment ``dz`` of the free unknowns to ``z`` in
  place (default ``z[free] += dz``; a model with rotations composes them multiplicatively);
* ``reference()``: the base configuration of the leading unknowns (coordinates and tangents that
  the unknowns displace), for the round-off floor of the residual;
* ``last_linear_info``: a dict set by ``solve_linear``; its ``note`` (a string, e.g. that an
  iterative solver broke down and another took over) is copied into the step's record;
* ``free_block(K)`` and ``product(K, v, absolute=False)``: the Jacobian on the free unknowns (what
  ``solve_linear`` takes) and ``K v`` (``|K| v``), for a Jacobian that is no scipy matrix (the
  distributed system's PETSc matrix, :mod:`mortar1d3d.distributed.system`); default
  ``K[free][:, free]`` and ``K @ v``;
* ``norm(v)``: the 2-norm of a vector of the loop (default ``np.linalg.norm``). A distributed
  system (:mod:`mortar1d3d.distributed.system`) hands the loop the entries this process owns:
  ``z``, ``r``, the increment, ``fixed`` and ``free`` are then local, every elementwise step runs
  on them unchanged, and ``norm`` is the global norm, the same on every process, so that every
  process takes the same decisions.
"""
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConvergenceError  # noqa: F401 (raised here; importable from here as before)


#: the round-off floor of a residual is taken as this many machine epsilons times ‖|K| (|z| + |X|)‖
#: (the size of the force terms that cancel in it); see :func:`_newton_step`
ROUNDOFF_FACTOR = 1e3

#: the linear solve of a Newton iteration leaves a linear residual of at most this times the
#: Newton target ``rtol ‖r_0‖`` of the load step (relative to its right-hand side, the current
#: residual ``r_k``: ``LINEAR_RTOL_FACTOR rtol ‖r_0‖ / ‖r_k‖``, at most :data:`LINEAR_RTOL_MAX`):
#: the step's first solve reduces by a tenth of ``rtol``, so one exactly solved step already meets
#: the target, and later solves ask only for what the target still needs instead of reducing an
#: already small residual by ``rtol`` again; their error stays a tenth of the target, so neither the
#: residual test nor quadratic convergence is held back, and the increment's error (about
#: ``0.1 rtol ‖Δz_0‖``) stays below ``increment_rtol ‖Δz_0‖`` for the default tolerances
LINEAR_RTOL_FACTOR = 0.1

#: the loosest relative tolerance a Newton iteration's linear solve gets (an inexact Newton
#: step reduces the linearised residual by at least this)
LINEAR_RTOL_MAX = 0.1


@dataclass
class StepRecord:
    """One converged load step.

    Attributes
    ----------
    load_factor : float
    iterations : int
        Newton iterations (linear solves) of this step.
    residuals : list of float
        ‖r_free‖ before each iteration and after the last one.
    increments : list of float
        ‖Δz‖ of each iteration.
    cuts : int
        How many times the step to this load factor was halved before it converged.
    time : float
        Wall time of the step in seconds.
    notes : list of str
        What the step log should say besides the numbers (e.g. that the linear solver of an
        iteration broke down and another one took over), each once.
    """

    load_factor: float
    iterations: int
    residuals: list = field(default_factory=list)
    increments: list = field(default_factory=list)
    cuts: int = 0
    time: float = 0.0
    notes: list = field(default_factory=list)


class _StepFailed(Exception):
    pass


def _magnitude(system, z):
    """``|z|`` plus the magnitude of the base configuration the leading unknowns displace."""
    size = np.abs(z)
    if hasattr(system, "reference"):
        X = np.abs(system.reference())
        size[: len(X)] += X
    return size


def _free_block(system, K):
    """The Jacobian on the free unknowns, what ``system.solve_linear`` takes."""
    own = getattr(system, "free_block", None)
    return K[system.free][:, system.free] if own is None else own(K)


def _norm(system, v):
    """The 2-norm of ``v`` (the system's own, global one if it has one)."""
    own = getattr(system, "norm", None)
    return float(np.linalg.norm(v)) if own is None else own(v)


def _product(system, K, v, absolute=False):
    """``K v``, or ``|K| v`` (entrywise absolute values) with ``absolute``."""
    own = getattr(system, "product", None)
    if own is not None:
        return own(K, v, absolute=absolute)
    return (abs(K) if absolute else K) @ v


def _newton_step(system, z, t, rtol, increment_rtol, max_iterations, divergence):
    """Iterate to equilibrium at load factor t from z (modified in place).

    Returns ``(residuals, increments, notes)``.
    """
    free = system.free
    z[system.fixed] = system.prescribed(t)
    residuals, increments, notes = [], [], []
    r0 = d0 = None
    for k in range(max_iterations + 1):
        try:
            r, K = system.residual(z, t, tangent=True)
        except (FloatingPointError, ValueError, ArithmeticError) as exc:
            raise _StepFailed(f"residual evaluation failed: {exc}") from None
        rn = _norm(system, r[free])
        residuals.append(rn)
        if not math.isfinite(rn):
            raise _StepFailed("the residual is not finite (NaN/inf: an element inverted or a "
                              "material left its admissible range)")
        if r0 is None:
            r0 = rn
            if rn == 0.0:
                return residuals, increments, notes
        else:
            # residual small relative to the first iteration, and either the last increment
            # small relative to the first one or the residual at round-off (it cannot fall further)
            if rn <= rtol * r0 and (increments[-1] <= increment_rtol * d0 or rn <= 1e-13 * r0):
                return residuals, increments, notes
            # round-off floor: very stiff terms (penalty, EA of slender beams) leave a residual that
            # cannot fall further; accept when the increment has converged and the residual is small
            if increments[-1] <= increment_rtol * d0 and rn <= math.sqrt(rtol) * r0:
                return residuals, increments, notes
            # with a very large penalty (or EA) the round-off of the force terms themselves can
            # exceed every relative target: accept once the residual is at that floor and the
            # increments no longer contract (they are round-off of the solve too). The terms are
            # formed from the current configuration X + z, whose entries carry round-off
            # eps_mach (|X| + |z|): a model far from the origin has a higher floor wherever a term
            # uses absolute positions (a follower pressure does; the beam, solid and coupling
            # kernels work relative to each element and stay below it).
            # (|K| is a copy of the tangent: formed only once the increments have stopped contracting)
            if len(increments) >= 2 and increments[-1] > 0.5 * increments[-2]:
                floor = ROUNDOFF_FACTOR * np.finfo(float).eps * _norm(
                    system, _product(system, K, _magnitude(system, z), absolute=True)[free])
                if rn <= floor:
                    return residuals, increments, notes
            if rn > divergence * r0:
                raise _StepFailed(f"the residual grew from {r0:.3e} to {rn:.3e} (diverging)")
        if k == max_iterations:
            raise _StepFailed(f"no convergence in {max_iterations} iterations (residual {r0:.3e} → {rn:.3e}, "
                              f"target {rtol * r0:.3e})")
        try:
            linear_rtol = min(LINEAR_RTOL_MAX, LINEAR_RTOL_FACTOR * rtol * r0 / rn)
            dz = system.solve_linear(_free_block(system, K), -r[free], z[free], rtol=linear_rtol)
        except Exception as exc:  # a singular or unsolvable tangent ends this attempt
            raise _StepFailed(f"the linear solve failed: {exc}") from None
        # not needed any more: dropped before the next evaluation, which can then refill its
        # values' memory instead of allocating new (mortar1d3d.model.tangent)
        K = None
        note = (getattr(system, "last_linear_info", None) or {}).get("note")
        if note and note not in notes:
            notes.append(note)
        dn = _norm(system, dz)
        if not math.isfinite(dn):
            raise _StepFailed("the Newton increment is not finite (singular tangent?)")
        update = getattr(system, "update", None)
        if update is None:
            z[free] += dz
        else:
            update(z, free, dz)
        increments.append(dn)
        if d0 is None:
            d0 = max(dn, 1e-300)


def solve_load_steps(system, z0, steps, *, rtol=1e-8, increment_rtol=1e-8, max_iterations=25, max_cuts=6,
                     divergence=1e6, progress=None):
    """Load factors ``1/steps, 2/steps, ..., 1``, each solved by Newton–Raphson.

    A step that fails (residual not finite, growing by more than ``divergence``, or not converged
    in ``max_iterations``) is retried from the last converged state with half the load increment,
    up to ``max_cuts`` times in a row; a converged cut step lets the increment grow back.

    Parameters
    ----------
    system : object
        See the module docstring.
    z0 : (n,) float64
        Start vector (the reference state, usually zeros).
    steps : int
    rtol, increment_rtol : float
        Convergence: ‖r_k‖ <= rtol ‖r_0‖ and ‖Δz_k‖ <= increment_rtol ‖Δz_0‖ (both relative to the
        first iteration of the step); or ‖r_k‖ <= 1e-13 ‖r_0‖; or, at a round-off floor of the
        residual, ‖Δz_k‖ <= increment_rtol ‖Δz_0‖ with ‖r_k‖ <= sqrt(rtol) ‖r_0‖; or, when the
        force terms are so large that their round-off exceeds these targets (penalty ≳ 1e7 E,
        follower loads on a model far from the origin), ‖r_k‖ <= ROUNDOFF_FACTOR eps_mach
        ‖|K| (|z| + |X|)‖ (X: ``system.reference()``, if given) once the increments stop
        contracting (‖Δz_k‖ > ‖Δz_{k-1}‖ / 2). The linear solve of iteration k is asked for the
        relative residual ``min(LINEAR_RTOL_MAX, LINEAR_RTOL_FACTOR rtol ‖r_0‖ / ‖r_k‖)``: a tenth
        of what the step's target still needs.
    progress : callable, optional
        ``progress(record, step_index, n_steps)`` after every converged step.

    Returns
    -------
    z : (n,) float64
        Converged unknowns at load factor 1.
    records : list of StepRecord
    history : list of (n,) float64
        Converged unknowns after each step.

    Raises
    ------
    ConvergenceError
        After ``max_cuts`` consecutive cuts; the message gives the load factor reached, the
        residual history of the last attempt, and what to try.
    """
    z = np.array(z0, dtype=float)
    t_done, base = 0.0, 1.0 / steps
    dt = base
    records, history = [], []
    cuts = 0
    while t_done < 1.0 - 1e-14:
        t = min(1.0, t_done + dt)
        trial = z.copy()
        start = time.perf_counter()
        try:
            residuals, increments, notes = _newton_step(system, trial, t, rtol, increment_rtol, max_iterations,
                                                        divergence)
        except _StepFailed as exc:
            cuts += 1
            if cuts > max_cuts:
                raise ConvergenceError(
                    f"Newton's method gave up at load factor {t:.6g} (last converged: {t_done:.6g}) after "
                    f"{max_cuts} step cuts (smallest increment {dt:.3g}): {exc}. "
                    "Try more load steps ([analysis] steps), check that the supports fix every rigid-body "
                    "motion, lower the penalty if the coupling is very stiff, or use a smaller load."
                ) from None
            dt *= 0.5
            continue
        z = trial
        t_done = t
        rec = StepRecord(load_factor=t, iterations=len(increments), residuals=residuals, increments=increments,
                         cuts=cuts, time=time.perf_counter() - start, notes=notes)
        records.append(rec)
        history.append(z.copy())
        if progress is not None:
            progress(rec, len(records), None)
        if dt < base:
            dt = min(base, 2.0 * dt)
        cuts = 0
    return z, records, history


def solve_linear_step(system, z0, *, t=1.0, started=None):
    """Solve a linear analysis in one step at load factor ``t``: the system linearised at ``z0``.

    The residual and its Jacobian ``K`` are evaluated once, at ``z0``; the fixed unknowns get
    their prescribed values and the free ones the solution of the reduced system, so that the
    linearised residual ``r(z0) + K (z - z0)`` vanishes on the free unknowns.

    Parameters
    ----------
    system : object
        See the module docstring.
    z0 : (n,) float64
        Start vector (the reference state, usually zeros); not modified.
    t : float
        Load factor.
    started : float, optional
        ``time.perf_counter()`` at which the step's wall time starts (default: now).

    Returns
    -------
    z : (n,) float64
        The solution.
    record : StepRecord
        One iteration: ``residuals`` ‖r_free‖ at ``z0`` and at ``z``, ``increments`` ‖(z - z0)_free‖.
    residual : (n,) float64
        The linearised residual ``r(z0) + K (z - z0)`` over all unknowns (its fixed entries are
        the reactions).
    """
    started = time.perf_counter() if started is None else started
    r0, K0 = system.residual(z0, t)
    z = z0.copy()
    z[system.fixed] = system.prescribed(t)
    free = system.free
    rhs = -(r0 + _product(system, K0, z - z0))[free]
    z[free] += system.solve_linear(_free_block(system, K0), rhs)
    residual = r0 + _product(system, K0, z - z0)
    note = (getattr(system, "last_linear_info", None) or {}).get("note")
    record = StepRecord(load_factor=t, iterations=1,
                        residuals=[_norm(system, r0[free]), _norm(system, residual[free])],
                        increments=[_norm(system, (z - z0)[free])], time=time.perf_counter() - started,
                        notes=[note] if note else [])
    return z, record, residual
