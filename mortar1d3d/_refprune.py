"""Letting Numba's reference-count pruning see through the calls between the package's kernels.

A compiled function increments the reference count of every array it receives when it starts and
decrements it at each of its returns (``NRT_incref`` / ``NRT_decref``, one atomic read-modify-write
each). The arguments are borrowed (the caller holds them for the whole call), so these pairs are
redundant, and Numba's LLVM pass ``refprune`` removes them where it can prove every path from the
increment reaches a decrement, or, with its raise-aware variant (``FANOUT_RAISE``), ends in a raise:
a block that stores an exception with the metadata ``numba_exception_output``.

After every call of another compiled function Numba tests the callee's status and, on an error,
returns it to its own caller (``CallConv.return_status_propagate``) without decrementing anything
and without that metadata. So a function that calls another one that LLVM does not inline, such as
the Newton projection calling the other element types' map through a symbol (``_map_other``), kept
every increment and decrement of its array arguments: 2 atomic operations per array and call, about
70 per integration point on the hex8 Newton path (``benchmarks/atomics.py`` counts them).

:func:`propagate_as_raise` marks the store of a propagated exception with the same metadata as a
raise, in the package's own functions only. A propagated error is a raise of the caller for every
purpose of the pass: the function returns it at once, and before this change it leaked the
argument references on that path anyway. With the mark the pass removes the pairs on the normal
paths and the increments, so an error path leaks nothing and the normal path pays nothing. The
emitted code is otherwise Numba's own (the original method runs unchanged; only the metadata is
added), so results are the same to the bit. On a Numba without the method's expected form (no
store of the exception pointer in the current block) nothing is marked: the code of before.
"""
from llvmlite import ir
from numba.core import callconv

#: functions of the package: their Numba symbols start with the package's length-prefixed name
_PACKAGE = "_ZN10mortar1d3d"
_MARK = "numba_exception_output"


def _marking(original):
    def return_status_propagate(self, builder, status):
        block = builder.block
        start = len(block.instructions)
        original(self, builder, status)
        if not builder.function.name.startswith(_PACKAGE):
            return
        for instruction in block.instructions[start:]:
            if isinstance(instruction, ir.StoreInstr) and instruction.operands[0] is status.excinfoptr:
                instruction.set_metadata(_MARK, builder.module.add_metadata([ir.IntType(1)(1)]))
                break

    return_status_propagate._marks_raise = True
    return return_status_propagate


def propagate_as_raise():
    """Mark the propagated errors of the package's compiled functions as raises (see the module's
    docstring); once per process, before any kernel is compiled (:mod:`mortar1d3d._config` calls it)."""
    method = callconv.CPUCallConv.return_status_propagate
    if getattr(method, "_marks_raise", False):
        return
    callconv.CPUCallConv.return_status_propagate = _marking(method)
