"""Calling MuJoCo's C functions from numba: their addresses in the libmujoco that the Python
bindings loaded, and intrinsics that call them with ``mjModel*``/``mjData*`` given as integers
(``MjModel._address``, ``MjData._address``)."""

from __future__ import annotations

import ctypes
import functools
import os

import mujoco
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

# MuJoCo's pipeline stages that the implicit scheme calls (bladelab.runner.implicit): positions
# (kinematics, centre-of-mass frames, mass matrix), velocities, bias and passive forces.
STAGES = ("mj_kinematics", "mj_comPos", "mj_crb", "mj_comVel", "mj_rne", "mj_passive")


@functools.cache
def _library() -> ctypes.CDLL:
    folder = os.path.dirname(mujoco.__file__)
    names = sorted(n for n in os.listdir(folder) if n.startswith("libmujoco.so"))
    return ctypes.CDLL(os.path.join(folder, names[-1]))


def mujoco_address(name: str) -> int:
    """Address of the C function ``name`` of libmujoco."""
    return ctypes.cast(getattr(_library(), name), ctypes.c_void_p).value


@functools.cache
def mujoco_step_addresses() -> tuple[int, int]:
    """Addresses of ``mj_step1`` and ``mj_step2`` in the libmujoco that the bindings loaded."""
    return mujoco_address("mj_step1"), mujoco_address("mj_step2")


def mujoco_stage_addresses() -> np.ndarray:
    """int64 addresses of :data:`STAGES`, in that order."""
    return np.array([mujoco_address(n) for n in STAGES], dtype=np.int64)


@intrinsic
def call_mujoco(typingctx, fptr, mptr, dptr):
    """Call ``void f(const mjModel*, mjData*)`` given the three addresses as integers."""
    sig = types.void(types.int64, types.int64, types.int64)

    def codegen(context, builder, signature, args):
        f, m, d = args
        i8p = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i8p])
        fn = builder.inttoptr(f, fnty.as_pointer())
        builder.call(fn, [builder.inttoptr(m, i8p), builder.inttoptr(d, i8p)])
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def call_mujoco_rne(typingctx, fptr, mptr, dptr, result):
    """Call ``mj_rne(m, d, 0, result)`` (bias forces, no acceleration term) given the four
    addresses as integers; ``result`` points to ``nv`` doubles."""
    sig = types.void(types.int64, types.int64, types.int64, types.int64)

    def codegen(context, builder, signature, args):
        f, m, d, r = args
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i8p, i32, i8p])
        fn = builder.inttoptr(f, fnty.as_pointer())
        builder.call(fn, [builder.inttoptr(m, i8p), builder.inttoptr(d, i8p), ir.Constant(i32, 0),
                          builder.inttoptr(r, i8p)])
        return context.get_dummy_value()

    return sig, codegen
