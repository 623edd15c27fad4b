"""The numba backend's evaluation of a Problem: the element's kernels and the loads' compiled
evaluations write the residual and the tangent straight into the CSR data of the assembler's
fixed pattern (``kernels.csr``); a load without a compiled evaluation is evaluated by NumPy and
its blocks scattered.  Built once per assembler and set of loads."""
from __future__ import annotations

import numpy as np

from ..errors import OptionError
from .base import Evaluation, force_scale_with_loads

__all__ = ["CompiledEvaluation"]

_NO_DATA = np.zeros(0)        # the CSR data of a residual-only evaluation


def _compiled_loads(loads, pattern):
    """[(load, compiled add or None)]: the magnetic loads (plain ``MagneticLoad``) batched into
    one entry (``magnetics.compiled_magnets``: one field evaluation per field and one kernel
    call for all of them), the others one by one."""
    from .magnetics import MagneticLoad, compiled_magnets
    mags = [ld for ld in loads if type(ld) is MagneticLoad]
    out = [(ld, ld.compiled(pattern)) for ld in loads if type(ld) is not MagneticLoad]
    if mags:
        out.append((mags, compiled_magnets(mags, pattern)))
    return out


def _checked_out(out, nnz):
    """``out`` if it is a writable C-contiguous float64 array of nnz entries (the kernels write
    the tangent into it by position, without bounds checks: a shorter array was written past its
    end, a float32 or strided one crashed the process), else an OptionError."""
    ok = (isinstance(out, np.ndarray) and out.dtype == np.float64 and out.shape == (nnz,)
          and out.flags.c_contiguous and out.flags.writeable)
    if not ok:
        raise OptionError(f"out must be a writable C-contiguous float64 array of the pattern's {nnz} entries "
                          f"(assembler.pattern().new_data()), got {type(out).__name__} "
                          f"{getattr(out, 'dtype', '')} of shape {getattr(out, 'shape', None)}")
    return out


def _same_objects(a, b):
    """True if the keys a and b, (assembler, element, tuple of loads), hold the same objects."""
    return a[0] is b[0] and a[1] is b[1] and len(a[2]) == len(b[2]) and all(x is y for x, y in zip(a[2], b[2]))


class CompiledEvaluation:
    """The compiled evaluation of ``problem`` (see the module docstring)."""

    def __init__(self, problem):
        self.problem = problem
        self._parts = self._frame_parts = None
        self._state = None            # (kernels, g) of the kernels' last evaluation

    def _linear_stress(self, kern, g, eta):
        """The kernels' linear stress about g (their workspace holds the last evaluated state:
        re-evaluate the residual at g first if another state came in between)."""
        if self._state is None or self._state[0] is not kern or self._state[1] is not g:
            kern.residual(g)
            self._state = (kern, g)
        return kern.linear_stress(np.ascontiguousarray(eta, dtype=float))

    def parts(self, asm, loads=None):
        """(pattern, element kernels, [(load, compiled add or None)]) for the assembler, built
        once and again when the loads change; None when the element has no kernels.  ``loads``:
        the problem's restated in other coordinates (``Problem.evaluate``'s frame_loads)."""
        prob = self.problem
        slot = "_parts" if loads is None else "_frame_parts"     # each kept: no rebuilds as they alternate
        loads = prob.loads if loads is None else loads
        # the objects themselves, compared by identity: their id()s alone are reused once they are
        # freed (a support added drops the assembler, or linear analysis evaluates on a temporary
        # one of all dofs, and the next one is often allocated at the same address: the old
        # pattern was kept, K 144 x 144 for 141 free dofs, a residual on 162 dofs for 144)
        key = (asm, prob.element, tuple(loads))
        parts = getattr(self, slot)
        if parts is None or not _same_objects(parts[0], key):
            pattern = asm.pattern()
            kern = prob.element.compiled(pattern)
            loads = _compiled_loads(loads, pattern) if kern is not None else []
            parts = (key, None if kern is None else (pattern, kern, loads))
            setattr(self, slot, parts)
        return parts[1]

    def evaluate(self, asm, g, lam, tangent, out, stress=None, loads=None):
        """The problem's Evaluation at (g, lam), or None when the element has no kernels
        (stress: a mixed element's independent stresses; loads: frame_loads, see
        ``Problem.evaluate``)."""
        from ..kernels import add_blocks
        parts = self.parts(asm, loads)
        if parts is None:
            return None
        pattern, kern, loads = parts
        g = np.ascontiguousarray(g, dtype=float)
        if tangent:
            data = pattern.new_data() if out is None else _checked_out(out, pattern.nnz)
            res = kern.tangent(g, data, stress=stress)
        else:
            data = _NO_DATA
            res = kern.residual(g)
        self._state = (kern, g)
        r_int = res["r"].copy()
        f = np.zeros((self.problem.mesh.n_nodes, 6))
        for ld, add in loads:
            if add is not None:
                add(g, lam, f, data, tangent)
                continue
            ev = ld.evaluate(g, lam, tangent).checked(ld, len(f), len(self.problem.mesh.quads))
            f += ev.f
            if tangent:
                add_blocks(data, pattern, self.problem.mesh.quads, ev.node_blocks, ev.element_blocks)
        scale = force_scale_with_loads(res["force_scale"], self.problem.loads, self.problem.length_scale)
        out_ev = Evaluation((r_int - f).ravel()[pattern.free], r_int, f, scale, res["energy"],
                            stress=res.get("stress"))
        if tangent and self.problem.element.mixed:
            out_ev.linearization = lambda eta, g=g: self._linear_stress(kern, g, eta)
        if tangent:
            out_ev.K = pattern.matrix(data)
        return out_ev
