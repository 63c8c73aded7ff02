"""One parallel loop, compiled once, for every kernel's workers.

A ``prange`` loop costs a cold compile about 0.6 CPU s whatever its body (benchmarks/README.md,
session fifteen): Numba types the loop's body again as a function of its own (the gufunc), builds a
wrapper and the launch, and each is optimised and turned into machine code. The kernels' parallel
loops are all alike: one iteration per worker (or per part), which allocates the worker's buffers
and claims chunks of work (:mod:`mortar1d3d._schedule`). :func:`in_parallel` runs such an iteration,
written as an ordinary compiled function ``worker(index, *args)``, for ``index`` in ``0..n-1`` on
Numba's threads through :func:`_drive`, the package's only ``prange`` loop of this kind, compiled
once and called through a symbol (:mod:`mortar1d3d._unlinked`)::

    @njit
    def _kernel_worker(worker, claims, n, a, out):
        buffer = np.empty(3)
        begin, stop = claim(claims, n, worker)
        ...

    _kernel_workers = in_parallel(_kernel_worker)

    @njit
    def kernel(a, out, workers):
        claims = new_claims(a.shape[0], workers)
        _kernel_workers(workers, claims, a.shape[0], a, out)    # was: for worker in prange(workers): ...

The call packs the arguments into a record on the caller's stack and hands :func:`_drive` the
record's address and a task: a small function the call defines in the caller's module, which
unpacks the record and calls the worker (compiled on its own, through its symbol). The worker does
what the loop's body did, in the same order, so results do not change. A worker that raises makes
the call raise ``RuntimeError`` after every worker has returned (the exception's own text is not
passed on: the kernels' workers raise only when a lazy callee cannot be compiled, which prints why).
The arguments are passed as they are (arrays by reference, no copy, no reference counting of the
record: the caller holds them for the call).
"""
import numba
from llvmlite import ir
from numba import prange, types
from numba.core import cgutils
from numba.extending import intrinsic

from ._config import njit_parallel
from ._unlinked import SUPPORTED_FROM, _argument_type, _register, _Reload, _symbol

#: a task: ``i32 task(i8* record, i64 index)``, 0 when the worker returned, 1 when it raised
_TASK = ir.FunctionType(ir.IntType(32), [cgutils.voidptr_t, ir.IntType(64)])


@intrinsic
def _run_task(typingctx, task, record, index):
    """``task(record, index)`` (``task`` and ``record`` addresses as integers): 0, or 1 if the worker raised."""
    def codegen(context, builder, signature, args):
        fn = builder.inttoptr(args[0], _TASK.as_pointer())
        status = builder.call(fn, [builder.inttoptr(args[1], cgutils.voidptr_t), args[2]])
        return builder.zext(builder.icmp_unsigned("!=", status, ir.Constant(status.type, 0)), ir.IntType(64))

    return types.int64(types.int64, types.int64, types.int64), codegen


@njit_parallel
def _drive(task, record, n):
    """Run ``task(record, i)`` for ``i`` in ``0..n-1`` on Numba's threads; returns how many raised."""
    failed = 0
    for i in prange(n):
        failed += _run_task(task, record, i)
    return failed


_DRIVE_ARGS = (types.int64, types.int64, types.int64)


def _define_task(context, module, record_type, symbol, worker_args):
    """The task of a call (defined once per caller module and worker signature): unpack the record,
    call the worker through its symbol, return 0, or 1 if it raised."""
    name = f"{symbol}.task"
    task = module.globals.get(name)
    if task is not None:
        return task
    task = ir.Function(module, _TASK, name)
    task.linkage = "internal"
    builder = ir.IRBuilder(task.append_basic_block("entry"))
    record = builder.bitcast(task.args[0], record_type.as_pointer())
    values = [builder.load(cgutils.gep_inbounds(builder, record, 0, k)) for k in range(len(record_type.elements))]
    fnty = context.call_conv.get_function_type(types.none, worker_args)
    fn = cgutils.get_or_insert_function(module, fnty, symbol)
    status, _ = context.call_conv.call_function(builder, fn, types.none, worker_args, [task.args[1]] + values)
    builder.ret(builder.select(status.is_error, ir.Constant(ir.IntType(32), 1), ir.Constant(ir.IntType(32), 0)))
    return task


def in_parallel(dispatcher):
    """A function for compiled code: ``call(n, *args)`` runs ``dispatcher(i, *args)`` (an
    :data:`~mortar1d3d._config.njit` kernel returning nothing, defined at module level) for ``i`` in
    ``0..n-1`` in parallel, as ``for i in prange(n): dispatcher(i, *args)`` would, without a
    ``prange`` loop of its own to compile (see the module's docstring). On a Numba older than
    :data:`~mortar1d3d._unlinked.SUPPORTED_FROM`: that loop (not cached)."""
    if tuple(numba.version_info.short) < SUPPORTED_FROM:
        @numba.njit(parallel=True)
        def loop(n, *args):
            for i in prange(n):
                dispatcher(i, *args)
        return loop

    module, qualname = dispatcher.py_func.__module__, dispatcher.py_func.__qualname__

    @intrinsic
    def call(typingctx, n, *args):
        worker_args = (types.int64,) + tuple(_argument_type(a) for a in args)
        cres = _register(dispatcher, worker_args)
        if cres.signature.return_type != types.none:
            raise TypeError(f"in_parallel: {qualname} must return nothing, it returns {cres.signature.return_type}")
        worker_args = cres.signature.args
        symbol = _symbol(dispatcher, worker_args)
        _register(_drive, _DRIVE_ARGS)
        hooks = (_Reload(module, qualname, worker_args), _Reload(__name__, "_drive", _DRIVE_ARGS))

        def codegen(context, builder, signature, packed):
            count = context.cast(builder, packed[0], signature.args[0], types.int64)
            values = [context.cast(builder, v, t, c) for v, t, c in
                      zip(cgutils.unpack_tuple(builder, packed[1]), signature.args[1].types, worker_args[1:])]
            record_type = ir.LiteralStructType([v.type for v in values])
            record = cgutils.alloca_once(builder, record_type)
            for k, value in enumerate(values):
                builder.store(value, cgutils.gep_inbounds(builder, record, 0, k))
            task = _define_task(context, builder.module, record_type, symbol, worker_args)
            drive = cgutils.get_or_insert_function(builder.module,
                                                   context.call_conv.get_function_type(types.int64, _DRIVE_ARGS),
                                                   _symbol(_drive, _DRIVE_ARGS))
            status, failed = context.call_conv.call_function(
                builder, drive, types.int64, _DRIVE_ARGS,
                [builder.ptrtoint(task, ir.IntType(64)), builder.ptrtoint(record, ir.IntType(64)), count])
            with cgutils.if_unlikely(builder, status.is_error):
                context.call_conv.return_status_propagate(builder, status)
            with cgutils.if_unlikely(builder, builder.icmp_signed(">", failed, ir.Constant(failed.type, 0))):
                context.call_conv.return_user_exc(builder, RuntimeError,
                                                  (f"mortar1d3d: a parallel worker of {qualname} raised",))
            context.active_code_library._reload_init.update(hooks)
            return context.get_dummy_value()

        return types.none(n, types.StarArgTuple.from_types(args)), codegen

    call.__name__ = call.__qualname__ = f"in_parallel_{dispatcher.py_func.__name__}"
    return call
