"""Launching the solver's Warp CPU kernels (:mod:`.kernels`): the same bits as numpy, or numpy.

The per-triangle steps of a local-global iteration (:func:`core.pattern.optimizer.steps.local_step`,
:func:`core.pattern.optimizer.feedback.move_corrections`, :func:`core.pattern.optimizer.steps.rhs_terms`,
:func:`core.pattern.optimizer.steps.collapse_guard`, :func:`core.pattern.optimizer.steps.flip_guard`,
:func:`core.pattern.optimizer.steps.realign_grain`) ask this module first; it returns None (False)
when numpy must do the step, and the step then runs its numpy code:

- the kernels are off (``EASE_SOLVER_KERNELS=numpy``, :func:`use`), Warp
  does not import, its compiler fails or it refuses a launch (one warning,
  then numpy for the process);
- a case the kernels do not cover: fewer than 8 triangles, column weights
  other than 1, an adaptation's feedback, a collapse guard whose gains numpy
  would leave over its limit, an input that is not an aligned contiguous
  native float64 (f,) array;
- a kernel flags a lane where Warp and numpy could part: a NaN meeting a
  min / max (Warp's ignore it, numpy's propagate it), a triangle the feedback
  leaves, a local step whose every ``delta`` is 0 (numpy skips its Newton step).

So a pattern is the same bytes either way (tests/test_pattern_kernels.py).
Outputs are new arrays every call, as numpy's are (the rows of one block: a
kept row keeps its block, e.g. the local step's warp factors its 7 rows).
Launches are Warp's recorded CPU launches (its public API only), kept per
thread, with only the arguments that changed rebound: an array by re-pointing
its slot's ``array_t`` value, never by wrapping it in a new ``wp.array``; a
thread keeps the launches of the last few sizes, and no array past its call.
"""

from __future__ import annotations

import ctypes
import logging
import math
import os
import threading
import weakref
from contextlib import contextmanager
from typing import Optional

import numpy as np

from ...progress import Progress, report

log = logging.getLogger(__name__)

#: Environment variable choosing the per-triangle steps' code: ``warp`` (default) or ``numpy``.
ENV = "EASE_SOLVER_KERNELS"
_LANES = 8
#: recorded launches a thread keeps, the most recently used: the 8 kernels at 4 sizes (a batch over many
#: designs, or the add-on over a session, meets a new size with every design)
_KEPT = 32
_state = {"ready": None, "forced": None}
_lock = threading.RLock()  # load() gives up under it
_local = threading.local()


def use(enabled: Optional[bool]) -> None:
    """Force the kernels on (True: if they load) or off (False), or follow :data:`ENV` again (None)."""
    _state["forced"] = enabled


def wanted() -> bool:
    """Whether the kernels are asked for: :func:`use`, else :data:`ENV`."""
    forced = _state["forced"]
    if forced is not None:
        return bool(forced)
    value = os.environ.get(ENV, "warp").strip().lower()
    if value not in ("warp", "numpy", ""):
        # a typo ("off", "0") must not silently mean the kernels: numpy, the reference, and say so once
        if not _state.get("env_warned"):
            _state["env_warned"] = True
            log.warning("%s=%r: expected warp or numpy; using numpy", ENV, value)
        return False
    return value != "numpy"


def enabled() -> bool:
    """Whether the kernels run: the choice of the solver whose call this is (:func:`chosen`), else
    :func:`wanted`; and loaded (compiled on first use; False after a failure)."""
    choice = getattr(_local, "chosen", None)
    return (wanted() if choice is None else choice) and load()


@contextmanager
def chosen(kernels: bool):
    """The steps this thread runs inside use the kernels or not as ``kernels`` says: the choice a
    :class:`core.pattern.optimizer.solver.PatternSolver` made once when it was built (:func:`core.pattern.accel.choose`),
    whatever :data:`ENV` or :func:`use` say meanwhile."""
    before = getattr(_local, "chosen", None)
    _local.chosen = bool(kernels)
    try:
        yield
    finally:
        _local.chosen = before


def load(progress: Optional[Progress] = None) -> bool:
    """Import Warp and load the kernels, compiling them on a machine's first run (~5 s of CPU, then cached
    in Warp's kernel cache); False, with one warning, where that fails."""
    if _state["ready"] is None:
        with _lock:
            if _state["ready"] is None:
                report(progress, 0.99, "loading the solver's kernels (compiled on the first run)")
                try:
                    from ...geom.queries import init_cpu
                    from . import kernels as K
                    from . import ldl_kernels, sparse_kernels

                    init_cpu()
                    K.wp.load_module(K, device="cpu")
                    K.wp.load_module(ldl_kernels, device="cpu")
                    K.wp.load_module(sparse_kernels, device="cpu")
                    _state["ready"] = True
                except Exception as exc:  # noqa: BLE001 - any failure leaves numpy, which gives the same bits
                    give_up("loading", exc)
    return bool(_state["ready"])


def give_up(doing: str, exc: Exception) -> None:
    """The kernels off for the process after ``exc`` while ``doing``: one warning, numpy (and qdldl) after."""
    with _lock:
        if _state["ready"] is not False:
            _state["ready"] = False
            log.warning(
                "pattern solver: Warp kernels unavailable (%s: %s: %s); using numpy", doing, type(exc).__name__, exc
            )


class _Unsuitable(Exception):
    """An argument the kernels do not take: numpy does the step."""


_F64 = np.dtype(np.float64)
_I32 = np.dtype(np.int32)


def _address(a: np.ndarray) -> int:
    # ctypes' view of the buffer is 3x quicker than ``a.ctypes.data``; a read-only array has none
    try:
        return ctypes.addressof(ctypes.c_char.from_buffer(a))
    except TypeError:
        return a.ctypes.data


def _pointer(a, f: int, counters: bool) -> int:
    """The data address of ``a``: an aligned, contiguous, native float64 (f,) array, or with ``counters``
    an int32 one (else :class:`_Unsuitable`: another dtype would be read past its end or as other bits).

    Float64 is compared by equality after identity: an array that came through pickle (a Dask
    worker's) has an equal dtype that is another object.
    """
    if type(a) is not np.ndarray:
        raise _Unsuitable
    flags = a.flags
    if not (flags.c_contiguous and flags.aligned):
        raise _Unsuitable
    if counters:
        if a.dtype is not _I32:
            raise _Unsuitable
    elif a.shape != (f,) or not (a.dtype is _F64 or a.dtype == _F64):
        raise _Unsuitable
    return _address(a)


class PerThread:
    """A holder of recorded launches per thread in ``self._local`` (a ``threading.local``: a launch keeps
    its argument struct, so threads never share one, and a finished thread's go with it); it pickles
    without them."""

    def __init__(self):
        self._local = threading.local()

    def __getstate__(self):
        state = dict(self.__dict__)
        del state["_local"]
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._local = threading.local()


#: an argument slot of a native-snippet kernel: an array of any dtype and length, bound by its address
_RAW = "raw"


def address(a: np.ndarray) -> int:
    """The data address of numpy array ``a`` (what :meth:`_Launch.bind` takes)."""
    return _address(a)


def native(kernel, args) -> "_Launch":
    """A recorded one-task CPU launch of native-snippet ``kernel`` (:mod:`.sparse_kernels`), run once on ``args``
    (numpy arrays, their dtypes the kernel's; scalars); then ``launch.bind(j, a, address(a))`` puts another
    array in slot ``j`` and ``launch()`` runs it. A launch is one thread's (it keeps its argument struct)."""
    from . import kernels as K

    slots = tuple(_RAW if K.wp.types.is_array(a.type) else None for a in kernel.adj.args)
    return _Launch(kernel, slots, args, 1, 0)


def _slots(kernel) -> tuple:
    """Per argument of ``kernel``: False (an (f,) float64 array read as 8-vectors), True (int32
    counters) or None (a scalar)."""
    from . import kernels as K

    return tuple((a.type.dtype is K.wp.int32) if K.wp.types.is_array(a.type) else None for a in kernel.adj.args)


class _Launch:
    """One recorded CPU launch of ``kernel`` over ``dim`` tasks on the arrays' elements from ``shift``.

    Recorded with Warp's public API (``wp.launch(record_cmd=True)``) on first
    use; then :meth:`bind` puts an argument into the recorded launch
    (``set_param_at_index``; an array as its ``array_t`` value, made once per
    slot from the recorded Warp array's ``__ctype__()`` and only re-pointed,
    so no Warp array is made per call) and :meth:`__call__` replays it.
    ``slots``: :func:`_slots` of ``kernel``.
    """

    def __init__(self, kernel, slots: tuple, args, dim: int, shift: int):
        from . import kernels as K

        wp = K.wp
        self.dim, self.shift, self.slots = dim, shift, slots
        inputs = []
        for a, counters in zip(args, slots):
            if counters == _RAW:
                inputs.append(wp.array(a, device="cpu", copy=False))
            elif counters:
                inputs.append(wp.array(a, dtype=wp.int32, device="cpu", copy=False))
            elif counters is not None:
                view = a[shift : shift + _LANES * dim].reshape(dim, _LANES)
                inputs.append(wp.array(view, dtype=K.v8, device="cpu", copy=False))
            else:
                inputs.append(a)
        # each array slot's value, owned here: a copy of the recorded array's (its data pointer and, for
        # a raw or counter slot, its length are rewritten by bind)
        self.values = [
            None if counters is None else type(x.__ctype__()).from_buffer_copy(x.__ctype__())
            for x, counters in zip(inputs, slots)
        ]
        self.cmd = cmd = wp.launch(kernel, dim=dim, inputs=inputs, device="cpu", record_cmd=True)
        cmd.launch()  # the first call's launch
        # the recorded launch keeps the first call's Warp arrays, and so its numpy arrays, for a graph
        # capture's replay, which these launches never are
        cmd.fwd_args = None

    def bind(self, j: int, a, address: Optional[int]) -> None:
        """Argument ``j`` is now ``a`` (an array at ``address``, or a scalar)."""
        if address is None:
            self.cmd.set_param_at_index(j, a)
            return
        counters = self.slots[j]
        value = self.values[j]
        if counters == _RAW:
            value.data, value.shape[0] = address, a.size
        elif counters:
            value.data, value.shape[0] = address, len(a)
        else:
            value.data = address + 8 * self.shift
        self.cmd.set_param_at_index_from_ctype(j, value)

    def __call__(self) -> None:
        self.cmd.launch()


class _Pair:
    """``kernel`` over the f // 8 blocks of 8 triangles and, where f % 8 != 0, once more over the 8 last
    (every kernel writes outputs only, so the overlap writes the same values twice).

    Only the arguments that are other objects than last time are rebound. The
    last call's arrays are known by weak references: a freed one is never taken
    for a new array at its address, and none is kept alive past its solve.
    """

    def __init__(self, kernel, f: int, head: tuple, out: np.ndarray, flags: Optional[np.ndarray]):
        self.slots = slots = _slots(kernel)
        args = (*head, *out) + (() if flags is None else (flags,))
        for a, counters in zip(args, slots):
            if counters is not None:
                _pointer(a, f, counters)
        self.f = f
        self.last = [a if counters is None else weakref.ref(a) for a, counters in zip(head, slots)]
        # recording runs the launches: this is also the first call
        self.launches = [_Launch(kernel, slots, args, f // _LANES, 0)]
        if f % _LANES:
            self.launches.append(_Launch(kernel, slots, args, 1, f - _LANES))

    def __call__(self, head: tuple, out: np.ndarray, flags: Optional[np.ndarray]) -> None:
        """Run on the inputs ``head``, the outputs: the rows of ``out`` (k, f), and ``flags``."""
        last = self.last
        for j, a in enumerate(head):
            counters = self.slots[j]
            if counters is None:
                if _same_scalar(a, last[j]):
                    continue
                address, kept = None, a
            else:
                if last[j]() is a:
                    continue
                address, kept = _pointer(a, self.f, counters), weakref.ref(a)
            for launch in self.launches:
                launch.bind(j, a, address)
            last[j] = kept
        # the outputs are new every call, made by _call: their rows' addresses follow from the block's
        base, row, j = _address(out), out.strides[0], len(head)
        for k in range(out.shape[0]):
            for launch in self.launches:
                launch.bind(j + k, out, base + k * row)
        if flags is not None:
            address = _address(flags)
            for launch in self.launches:
                launch.bind(j + out.shape[0], flags, address)
        for launch in self.launches:
            launch()


def _same_scalar(a, b) -> bool:
    """Whether scalars ``a`` and ``b`` are the same number to the bit: 0.0 == -0.0, but a kernel may
    tell them apart (a product's sign); NaN is never the same."""
    return a == b and (a != 0 or math.copysign(1.0, a) == math.copysign(1.0, b))


def _run(kernel, f: int, head: tuple, out: np.ndarray, flags: Optional[np.ndarray]) -> None:
    """One call of ``kernel`` (:class:`_Pair`, the last :data:`_KEPT` kept per thread: each thread binds
    its own argument structs) on the inputs ``head``, the rows of ``out`` (k, f) and ``flags``."""
    cache = getattr(_local, "launches", None)
    if cache is None:
        cache = _local.launches = {}
    key = (kernel.key, f)
    pair = cache.pop(key, None)
    if pair is not None:
        cache[key] = pair  # the most recently used last
        pair(head, out, flags)
        return
    pair = _Pair(kernel, f, head, out, flags)  # recording runs the launches: this is also the call
    if len(cache) >= _KEPT:
        del cache[next(iter(cache))]
    cache[key] = pair


def _call(kernel, f: int, head: tuple, n_out: int, n_flags: int = 0):
    """``kernel`` on ``head`` (its inputs), ``n_out`` new (f,) outputs (the rows of one allocation) and
    ``n_flags`` counters zeroed: (outputs, counters), or None where the kernels do not apply (off, f < 8,
    an unsuitable argument)."""
    if f < _LANES or not enabled():
        return None
    block = np.empty((n_out, f))
    flags = np.zeros(n_flags, np.int32)
    try:
        _run(kernel, f, head, block, flags if n_flags else None)
        out = list(block)
    except _Unsuitable:
        return None
    except Exception as exc:  # noqa: BLE001 - a launch Warp refuses leaves numpy, as a failed load does
        give_up("launching " + kernel.key, exc)
        return None
    return out, flags


def _kernels():
    from . import kernels

    return kernels


def local_step(M, d0, d1, k, kprod, T, sw, warp_row: float, free: bool, lo: float, hi: float):
    """:func:`.steps.local_step`'s rest shapes and targets with unit column weights: (RT, T, sw) or None.

    ``kprod``: the two products of ``K'`` (``Cdiff``, ``C01``); ``sw`` the
    last warp factors (None: none yet); ``lo``, ``hi`` their bounds where
    ``free``. Returns the rest shapes (4 (f,)), the ease target (4 (f,)) and
    the new warp factors (None unless ``free``).
    """
    head = (
        *M,
        d0,
        d1,
        *k,
        *kprod,
        T[2],
        T[3],
        d1 if sw is None else sw,
        int(sw is not None),
        float(warp_row),
        int(free),
        float(lo),
        float(hi),
    )
    got = _call(_kernels().local_step8, len(d0), head + (1,), 7, 2)
    if got is not None and not got[1][0]:
        # every delta 0: numpy takes no Newton step (the kernel's is a no-op only to round-off)
        got = _call(_kernels().local_step8, len(d0), head + (0,), 7, 2)
    if got is None or got[1][1]:
        return None
    out = got[0]
    if free:
        return out[:4], [T[0], T[1], out[4], out[5]], out[6]
    return out[:4], T, None


def ratios(M, Kc, c_weft, c_warp):
    """:func:`.feedback.move_corrections`' ratios ``c / rho`` (weft, warp) (f,) of a solve aimed at its own
    targets, or None (then numpy; also when a triangle is left out of the feedback)."""
    got = _call(_kernels().ratios8, len(c_weft), (*M, *Kc, c_weft, c_warp), 2, 1)
    return None if got is None or got[1][0] else got[0]


def corrections(
    p_w, p_g, corr_w: np.ndarray, corr_g: np.ndarray, lower: float, upper: float, floor: float, hi: float
) -> bool:
    """:func:`.feedback.move_corrections`' last steps: ``corr *= clip(p, lower, upper)`` for each of
    ``p_w``, ``p_g`` (f,) that is not None (the ratios to their gains, numpy's power), then every
    correction clipped to ``[floor, hi]``; ``corr_w``, ``corr_g`` (f,) updated in place. False (both
    untouched) where numpy must."""
    got = _call(
        _kernels().corrections8,
        len(corr_w),
        (
            corr_w if p_w is None else p_w,
            corr_g if p_g is None else p_g,
            corr_w,
            corr_g,
            int(p_w is not None),
            int(p_g is not None),
            float(lower),
            float(upper),
            float(floor),
            float(hi),
        ),
        2,
        1,
    )
    if got is None or got[1][0]:
        return False
    corr_w[:] = got[0][0]
    corr_g[:] = got[0][1]
    return True


def rhs_terms(RT, T, lam_reg: float, lam_ease: float):
    """:func:`.steps.rhs_terms` (4 new (f,) arrays), or None."""
    got = _call(_kernels().rhs_terms8, len(RT[0]), (*RT, *T, float(lam_reg), int(lam_reg != 1.0), float(lam_ease)), 4)
    return None if got is None else got[0]


def _body_weights(body: np.ndarray) -> np.ndarray:
    """The body triangles' mask (f,) bool as 0. / 1. (the kernel's lanes are float64), kept per mask."""
    kept = getattr(_local, "body", None)
    if kept is None or kept[0] is not body:
        kept = _local.body = (body, body.astype(np.float64))
    return kept[1]


def collapse_guard(guard, M, inverse, c_weft, c_warp, gain: np.ndarray):
    """:func:`.steps.collapse_guard`'s relative Jacobians ``q`` (4 (f,)), ``gain`` updated in place; or
    None (``gain`` untouched; numpy then: also for a guard that lowers gains as it raises them,
    ``guard_grow`` or ``guard_limit`` under 1, and where a gain under the guard is over ``guard_limit``,
    as after a resumed solve's escalated limit)."""
    if not (guard.guard_grow >= 1.0 and guard.guard_limit >= 1.0):
        return None
    (i00, i01, i10, i11), body = inverse
    got = _call(
        _kernels().guard8,
        len(gain),
        (
            *M,
            i00,
            i01,
            i10,
            i11,
            _body_weights(body),
            c_weft,
            c_warp,
            float(guard.guard_scale),
            float(guard.guard_open),
            float(guard.guard_grow),
            float(guard.guard_limit),
            float(guard.guard_release),
            gain,
        ),
        5,
        1,
    )
    if got is None or got[1][0]:
        return None
    gain[:] = got[0][0]
    return got[0][1:]


def grain_votes(M, wx, wy, vote):
    """:func:`.steps.realign_grain`'s per-triangle votes ``(w ix, w iy)`` (f,) each, or None."""
    got = _call(_kernels().votes8, len(vote), (*M, wx, wy, vote), 2, 1)
    return None if got is None or got[1][0] else got[0]


def turned(M, ct, st):
    """The Jacobians ``M`` turned by per-triangle cosines ``ct`` and sines ``st`` (4 (f,)), or None."""
    got = _call(_kernels().turn8, len(ct), (*M, ct, st), 4)
    return None if got is None else got[0]


def flip_check(blocks, U_new: np.ndarray, s_old: np.ndarray):
    """:func:`.steps.flip_guard`'s first check of a step ``U_new`` (n, 2) from an iterate of signed areas
    ``s_old`` (f,): (the step's signed areas (f,), how many triangles are at or under their floor), or
    None. The corners' coordinates are gathered by numpy (a gather is no faster in a kernel)."""
    F0, F1, F2 = blocks.face_columns
    if len(F0) < _LANES or not enabled():
        return None  # numpy's guard gathers the corners itself: not twice
    u, v = U_new[:, 0], U_new[:, 1]
    got = _call(_kernels().areas8, len(F0), (u[F0], v[F0], u[F1], v[F1], u[F2], v[F2], blocks.area_floor, s_old), 1, 2)
    return None if got is None or got[1][1] else (got[0][0], int(got[1][0]))
