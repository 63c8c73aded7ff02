"""Calling a compiled kernel without compiling its code into the caller again.

Numba links the code of every function a kernel calls into the kernel's own LLVM module and
optimises the whole again (so that it can inline it); a ``prange`` kernel does so twice (its
parallel body, then the kernel that launches it). A large function called once per chunk of
work gains nothing from being inlined, but its code is optimised three times.
:func:`unlinked` wraps such a function: a call through the wrapper compiles the function on its
own (or loads it from the cache) and calls it through an external symbol, so the caller's module
holds a declaration only.

The symbol's name is derived from the function's module, name and argument types, not from
Numba's per-process names, and it is registered with LLVM's symbol table (``add_symbol``) before
any code using it is loaded: when the caller is compiled (the callee is compiled while the call
is typed) and, through Numba's ``reload_init`` hook of a compiled function, before a cached caller
is loaded in another process (which loads or compiles the callee first). The caller stays
cachable: no address is frozen into its code.

It is used where a callee is large and its call is rare or carries much work: chunk functions of
``prange`` kernels, the solid's element kernel, the rare path of locating a point, and the element
dispatch's kernels of every type but the hot one (:func:`mortar1d3d.elements.selector.kernel_selector`).

**Lazy calls** (``unlinked(kernel, returns=TYPE)``): the callee is not compiled when the caller is
typed but at its first call. The caller loads the callee's address from a slot (a pointer-sized
cell this module allocates, registered under a stable symbol as above) and, while the slot is
empty, calls this module's resolver (a ``ctypes`` callback, also registered by name), which
compiles or loads the callee and fills the slot. So a scene compiles only the callees it reaches:
the other element types' kernels, the other types' map and Jacobian, the rare path of locating a
point. The callee's return type must be given (the caller is typed without typing the callee); the
resolver checks it against the compiled callee's and leaves the slot empty on a mismatch or a
compile error, and the caller then raises instead of calling. A cached caller's hook registers the
slot and the resolver only, without compiling the callee. :func:`compile_lazy` compiles every lazy
callee declared so far in the process (what :func:`mortar1d3d.warmup` does last, so that a warmed
cache holds them all).

This reaches into Numba's internals (the code library's ``_reload_init``, ``CompileResult._rebuild``,
the calling convention),
which ``tests/test_unlinked.py`` checks on the Numba the tests run with. On a Numba older than the
one it was written for (:data:`SUPPORTED_FROM`), :func:`unlinked` returns the kernel itself: an
ordinary call, compiled into the caller as before (the same results, a longer first compile).

Kernels calling through :func:`unlinked` may be called from other compiled functions at any
depth (the element dispatch of :mod:`mortar1d3d.elements.solid.dispatch` is called from most
kernels). Numba passes a callee's hooks on to a caller compiled in the same process (the caller
links the callee's library and inherits its ``_reload_init``), but a callee loaded from the cache
comes with an empty ``_reload_init`` on its library (the hooks are kept on the compile result
only), so a caller compiled in a process that loaded the callee from the cache would be cached
without them, and a later process loading that caller would meet an unresolved symbol.
:func:`_keep_hooks_on_load` therefore puts this module's hooks back on the library of every
compile result Numba rebuilds from the cache (Numba's ``CompileResult._rebuild``, wrapped once;
other hooks are left as they are).
"""

#: the oldest Numba whose internals :func:`unlinked` was written and tested against
SUPPORTED_FROM = (0, 68)
import ctypes
import hashlib
import importlib
import sys
import threading

import numba
from llvmlite import binding as ll
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic


def _symbol(dispatcher, argtypes):
    py = dispatcher.py_func
    key = hashlib.sha1(repr(tuple(argtypes)).encode()).hexdigest()[:16]
    return f"mortar1d3d.unlinked.{py.__module__}.{py.__qualname__}.{key}"


def _register(dispatcher, argtypes):
    """Compile (or load) ``dispatcher`` for ``argtypes`` and register its entry point under the
    stable symbol name; returns the compile result."""
    dispatcher.compile(tuple(argtypes))   # compiles, loads from the cache or finds the loaded one
    cres = dispatcher.overloads[tuple(argtypes)]
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    ll.add_symbol(_symbol(dispatcher, argtypes), address)
    return cres


def _keep_hooks_on_load():
    """Wrap Numba's ``CompileResult._rebuild`` (a cache load) so that the rebuilt library carries
    the :class:`_Reload` hooks of its compile result, as a freshly compiled one does."""
    from numba.core.compiler import CompileResult

    rebuild = CompileResult._rebuild.__func__
    if getattr(rebuild, "_keeps_unlinked_hooks", False):
        return

    def _rebuild(cls, *args, **kwargs):
        cres = rebuild(cls, *args, **kwargs)
        if cres.reload_init:
            cres.library._reload_init.update(h for h in cres.reload_init if isinstance(h, _Reload))
        return cres

    _rebuild._keeps_unlinked_hooks = True
    CompileResult._rebuild = classmethod(_rebuild)


class _Reload:
    """Numba's ``reload_init`` hook of a caller: registers its callee's symbol before the caller's
    cached code is loaded (picklable: holds the callee by module and name)."""

    def __init__(self, module, qualname, argtypes):
        self.module, self.qualname, self.argtypes = module, qualname, tuple(argtypes)

    def _dispatcher(self):
        dispatcher = importlib.import_module(self.module)
        for name in self.qualname.split("."):
            dispatcher = getattr(dispatcher, name)
        return dispatcher

    def __call__(self):
        _register(self._dispatcher(), self.argtypes)

    def _key(self):
        return self.module, self.qualname, self.argtypes

    def __eq__(self, other):
        return isinstance(other, _Reload) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())


#: the resolver's symbol: a lazy caller calls it with its slot while the slot is empty
_RESOLVE = "mortar1d3d.unlinked.resolve"
#: lazy callees by symbol: [slot (a ctypes pointer cell), dispatcher, argument types, return type]
_LAZY = {}
#: lazy callees by slot address (what the resolver is called with)
_BY_SLOT = {}
#: why a lazy callee could not be compiled, by symbol (its caller raises)
FAILED = {}
_lock = threading.RLock()


def _resolve(slot_address):
    """The resolver: compile (or load) the lazy callee of the slot at ``slot_address`` and fill the
    slot with its entry point. Called from compiled code (any thread; ``ctypes`` takes the GIL);
    an error is recorded in :data:`FAILED`, printed, and leaves the slot empty."""
    with _lock:
        symbol = _BY_SLOT[slot_address]
        slot, dispatcher, argtypes, restype = _LAZY[symbol]
        if slot.value:
            return
        try:
            cres = _register(dispatcher, argtypes)
            if cres.signature.return_type != restype:
                raise TypeError(f"{dispatcher.py_func.__qualname__}{argtypes} returns {cres.signature.return_type}, "
                                f"its lazy call was declared with {restype}")
            slot.value = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
        except Exception as error:     # noqa: BLE001 (reported to the caller, which raises)
            FAILED[symbol] = repr(error)
            print(f"mortar1d3d: could not compile {symbol}: {error!r}", file=sys.stderr, flush=True)


_resolver = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(_resolve)


def _declare_lazy(dispatcher, argtypes, restype):
    """Register the slot of a lazy callee (and the resolver) with LLVM's symbol table, without
    compiling the callee; returns the slot's symbol."""
    symbol = "mortar1d3d.unlinked_slot." + _symbol(dispatcher, argtypes)
    with _lock:
        if symbol not in _LAZY:
            if not _LAZY:
                ll.add_symbol(_RESOLVE, ctypes.cast(_resolver, ctypes.c_void_p).value)
            slot = ctypes.c_void_p(0)
            _LAZY[symbol] = [slot, dispatcher, tuple(argtypes), restype]
            _BY_SLOT[ctypes.addressof(slot)] = symbol
            ll.add_symbol(symbol, ctypes.addressof(slot))
    return symbol


class _LazyReload(_Reload):
    """The ``reload_init`` hook of a lazy caller: declares the callee's slot, compiles nothing."""

    def __init__(self, module, qualname, argtypes, restype):
        super().__init__(module, qualname, argtypes)
        self.restype = restype

    def __call__(self):
        _declare_lazy(self._dispatcher(), self.argtypes, self.restype)

    def _key(self):
        return super()._key() + (self.restype,)


def compile_lazy():
    """Compile (or load) every lazy callee declared in this process that has not been called yet,
    and those that compiling them declares in turn; returns how many."""
    done = 0
    while True:
        with _lock:
            waiting = [ctypes.addressof(entry[0]) for entry in _LAZY.values() if not entry[0].value]
        waiting = [address for address in waiting if _BY_SLOT[address] not in FAILED]
        if not waiting:
            return done
        for address in waiting:
            _resolve(address)
            done += 1


def unlinked(dispatcher, returns=None, cases=None):
    """A function for compiled code to call ``dispatcher`` (an :data:`~mortar1d3d._config.njit`
    kernel, defined at module level) without its code being compiled into the caller (on a Numba
    older than :data:`SUPPORTED_FROM`: ``dispatcher`` itself, an ordinary call).

    For large callees called a few times per kernel call (once per chunk of a ``prange`` loop):
    the call cannot be inlined, which costs nothing there, and the callee is optimised once.
    Arguments are passed as in an ordinary call (arrays by reference); the callee's return value is
    returned.

    ``returns``: the callee's Numba return type (``numba.types.none`` for a kernel returning
    nothing) makes the call lazy: the callee is compiled at its first call, not with the caller
    (for callees that a scene may never reach). The call then loads the entry point from a slot
    and tests it, a few instructions more per call.

    ``cases``: integers the first argument takes (e.g. the beam types' codes), for a callee
    returning nothing (``returns=types.none``). The callee is then compiled once per value, each
    with its first argument a literal (a compile-time constant: a ``select(code, name)`` in it picks
    its type's kernels), lazily; the call picks the value's version at run time (no call for a value
    not listed). A loop over types thus compiles only the types a scene has.
    """

    if tuple(numba.version_info.short) < SUPPORTED_FROM:
        return dispatcher
    _keep_hooks_on_load()
    module, qualname = dispatcher.py_func.__module__, dispatcher.py_func.__qualname__

    if cases is not None and returns != types.none:
        raise ValueError("unlinked(..., cases=...) takes a callee returning nothing (returns=types.none)")

    @intrinsic
    def call(typingctx, *args):
        argtypes = tuple(_argument_type(a) for a in args)
        if cases is not None:
            variants = {k: (types.literal(k),) + argtypes[1:] for k in cases}
            symbols = {k: _declare_lazy(dispatcher, variants[k], returns) for k in cases}
            hooks = [_LazyReload(module, qualname, variants[k], returns) for k in cases]

            def codegen(context, builder, signature, packed):
                values = cgutils.unpack_tuple(builder, packed[0])
                code = values[0]      # an integer: the literal's data model is the same
                end = builder.append_basic_block("unlinked.end")
                switch = builder.switch(code, end)
                for k in cases:
                    block = builder.append_basic_block(f"unlinked.case{k}")
                    switch.add_case(ir.Constant(code.type, k), block)
                    builder.position_at_end(block)
                    callee_args = variants[k]
                    rest = [context.cast(builder, v, t, c)
                            for v, t, c in zip(values[1:], signature.args[0].types[1:], callee_args[1:])]
                    fnty = context.call_conv.get_function_type(returns, callee_args)
                    fn = _load_lazy(context, builder, fnty, symbols[k])
                    status, _ = context.call_conv.call_function(builder, fn, returns, callee_args, [code] + rest)
                    with cgutils.if_unlikely(builder, status.is_error):
                        context.call_conv.return_status_propagate(builder, status)
                    builder.branch(end)
                builder.position_at_end(end)
                context.active_code_library._reload_init.update(hooks)
                return context.get_dummy_value()

            return returns(types.StarArgTuple.from_types(args)), codegen
        if returns is None:
            cres = _register(dispatcher, argtypes)
            restype, callee_args = cres.signature.return_type, cres.signature.args
            symbol = _symbol(dispatcher, argtypes)
            hook = _Reload(module, qualname, argtypes)
        else:
            restype, callee_args = returns, argtypes
            symbol = _declare_lazy(dispatcher, argtypes, returns)
            hook = _LazyReload(module, qualname, argtypes, returns)

        def codegen(context, builder, signature, packed):
            # the arguments arrive as one tuple (``*args``)
            values = cgutils.unpack_tuple(builder, packed[0])
            values = [context.cast(builder, v, t, c) for v, t, c in zip(values, signature.args[0].types, callee_args)]
            fnty = context.call_conv.get_function_type(restype, callee_args)
            if returns is None:
                fn = cgutils.get_or_insert_function(builder.module, fnty, symbol)
            else:
                fn = _load_lazy(context, builder, fnty, symbol)
            status, result = context.call_conv.call_function(builder, fn, restype, callee_args, values)
            with cgutils.if_unlikely(builder, status.is_error):
                context.call_conv.return_status_propagate(builder, status)
            context.active_code_library._reload_init.add(hook)
            return result

        return restype(types.StarArgTuple.from_types(args)), codegen

    call.__name__ = call.__qualname__ = f"unlinked_{dispatcher.py_func.__name__}"
    return call


def _argument_type(argtype):
    """The callee's type of an argument: not a literal, and a uint64 passed as an int64. A ``prange`` index is
    an int64 when its kernel is typed and a uint64 in the parallel body typed afterwards: one signature
    of the callee instead of two (the same value: an index is far below 2**63)."""
    argtype = types.unliteral(argtype)
    return types.int64 if argtype == types.uint64 else argtype


def _load_lazy(context, builder, fnty, symbol):
    """The entry point in the slot ``symbol`` (one load and test once the slot is filled); the
    resolver is called while it is empty, and the caller raises if it stays empty (the callee could
    not be compiled)."""
    module = builder.module
    slot = module.globals.get(symbol)
    if slot is None:
        slot = ir.GlobalVariable(module, fnty.as_pointer(), symbol)
        slot.linkage = "external"
    loaded = builder.load(slot)
    filled = builder.block
    with builder.if_then(cgutils.is_null(builder, loaded), likely=False):
        resolve = cgutils.get_or_insert_function(module, ir.FunctionType(ir.VoidType(), [cgutils.voidptr_t]), _RESOLVE)
        builder.call(resolve, [builder.bitcast(slot, cgutils.voidptr_t)])
        resolved = builder.load(slot)
        with cgutils.if_unlikely(builder, cgutils.is_null(builder, resolved)):
            context.call_conv.return_user_exc(builder, RuntimeError, ("mortar1d3d: a lazily compiled kernel could "
                                                                      "not be compiled (see mortar1d3d._unlinked.FAILED)",))
        after = builder.block
    fn = builder.phi(loaded.type)
    fn.add_incoming(loaded, filled)
    fn.add_incoming(resolved, after)
    return fn
