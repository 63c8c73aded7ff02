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
import hashlib
import importlib

import numba
from llvmlite import binding as ll
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

    def __call__(self):
        dispatcher = importlib.import_module(self.module)
        for name in self.qualname.split("."):
            dispatcher = getattr(dispatcher, name)
        _register(dispatcher, self.argtypes)

    def _key(self):
        return self.module, self.qualname, self.argtypes

    def __eq__(self, other):
        return isinstance(other, _Reload) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())


def unlinked(dispatcher):
    """A function for compiled code to call ``dispatcher`` (an :data:`~mortar1d3d._config.njit`
    kernel, defined at module level) without its code being compiled into the caller (on a Numba
    older than :data:`SUPPORTED_FROM`: ``dispatcher`` itself, an ordinary call).

    For large callees called a few times per kernel call (once per chunk of a ``prange`` loop):
    the call cannot be inlined, which costs nothing there, and the callee is optimised once.
    Arguments are passed as in an ordinary call (arrays by reference); the callee's return value is
    returned.
    """

    if tuple(numba.version_info.short) < SUPPORTED_FROM:
        return dispatcher
    _keep_hooks_on_load()

    @intrinsic
    def call(typingctx, *args):
        argtypes = tuple(types.unliteral(a) for a in args)
        cres = _register(dispatcher, argtypes)
        restype = cres.signature.return_type
        callee_args = cres.signature.args
        symbol = _symbol(dispatcher, argtypes)
        hook = _Reload(dispatcher.py_func.__module__, dispatcher.py_func.__qualname__, argtypes)

        def codegen(context, builder, signature, packed):
            # the arguments arrive as one tuple (``*args``)
            values = cgutils.unpack_tuple(builder, packed[0])
            values = [context.cast(builder, v, t, c) for v, t, c in zip(values, signature.args[0].types, callee_args)]
            fnty = context.call_conv.get_function_type(restype, callee_args)
            fn = cgutils.get_or_insert_function(builder.module, fnty, symbol)
            status, result = context.call_conv.call_function(builder, fn, restype, callee_args, values)
            with cgutils.if_unlikely(builder, status.is_error):
                context.call_conv.return_status_propagate(builder, status)
            context.active_code_library._reload_init.add(hook)
            return result

        return restype(types.StarArgTuple.from_types(args)), codegen

    call.__name__ = call.__qualname__ = f"unlinked_{dispatcher.py_func.__name__}"
    return call
