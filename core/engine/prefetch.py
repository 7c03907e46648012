"""A hint to the CPU to fetch a cell's cache line ahead of its use, for the kernel.

The kernel walks a tile's rows 64 cells at a time; the next row of each of
the world's arrays lies a whole world-row further on, a jump that the CPU's
own prefetchers do not follow, so every row would otherwise wait on memory
for each array's first line. :func:`prefetch` asks for the line early (LLVM's
``llvm.prefetch``: a read, kept close). It changes no value, and costs nothing
when the line is already there; an address outside the array is never faulted on,
but the kernel asks only for cells inside it.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

_READ, _KEEP_CLOSE, _DATA = 0, 3, 1  # llvm.prefetch's arguments: read or write, locality 0..3, data or instructions


@intrinsic
def prefetch(typingctx, array, y, x):
    """Ask for the cache line of ``array[y, x]`` (a 2-D array, unsigned indices inside it)."""
    if not (isinstance(array, types.Array) and array.ndim == 2 and isinstance(y, types.Integer) and isinstance(x, types.Integer)):
        return None

    def codegen(context, builder, signature, args):
        array_type = signature.args[0]
        view = context.make_array(array_type)(context, builder, args[0])
        pointer = cgutils.get_item_pointer(context, builder, array_type, view, [args[1], args[2]], wraparound=False)
        byte_pointer = builder.bitcast(pointer, ir.IntType(8).as_pointer())
        i32 = ir.IntType(32)
        hint = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [byte_pointer.type, i32, i32, i32]), "llvm.prefetch.p0"
        )
        builder.call(hint, [byte_pointer, ir.Constant(i32, _READ), ir.Constant(i32, _KEEP_CLOSE), ir.Constant(i32, _DATA)])
        return context.get_dummy_value()

    return types.void(array, y, x), codegen
