"""The compiled step of ``N`` robots (numba): the single robot's step over the columns of the ``(F, N)`` block in one
compiled loop; with ideal actuators and no per-step draws, three loops with ``tan`` and ``exp`` (:data:`NUMPY_SIMD`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.paths.clothoid import P_TAIL, SAMPLE_SPACING, ClothoidPath
from amigo_gym.paths.families import FAMILY_SEGMENTS, SEGMENT_FAMILIES
from amigo_gym.sim import fast_v1, layout_v1
from amigo_gym.task import v1 as tracking

#: numpy's float64 ``tan`` and ``exp`` are SIMD (SVML) on AVX-512 CPUs, faster on the calling thread than libm's on
#: fewer than about 8 to 11 of numba's threads: there the parallel step takes numpy's (docs/performance_log.md)
NUMPY_UMATH = (getattr(np, "_core", None) or np.core)._multiarray_umath  # numpy 2, else 1: its CPU features
NUMPY_SIMD = bool(getattr(NUMPY_UMATH, "__cpu_features__", {}).get("AVX512_SKX"))

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


def loop(name: str, parallel: bool) -> Any:
    """The compiled loop ``name`` of :mod:`amigo_gym.sim._kernels_v1`, or its twin on numba's threads
    (``name_parallel``: the same source, the same bits)."""
    return getattr(fast_v1.kernels(), name + ("_parallel" if parallel else ""))


class PathArena:
    """The flattened paths of ``n`` rows in one float64 array :attr:`flat`: row ``i``'s is
    ``flat[starts[i]:stops[i]]``. A path object is stored once while rows use it, a path :meth:`build` writes for its
    row alone; one that does not fit is appended after compacting the live paths if they fill <= 3/4 of :attr:`flat`,
    else after doubling it."""

    def __init__(self, n: int, parallel: bool = False) -> None:
        self.parallel = parallel  # the builds' loop on numba's threads
        self.flat: Array = np.zeros(1024)
        self.used = 0
        self.starts: IntArray = np.zeros(n, dtype=np.int64)
        self.stops: IntArray = np.zeros(n, dtype=np.int64)
        self._row_ids: list[int] = [0] * n  # id of each row's path (0: none)
        self._live: dict[int, list[Any]] = {}  # key (a path's id, or < 0 for a built row) -> [path, start, stop, rows]
        self._dead = 0
        self._key = 0

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        new = {oid: id(entry[0]) if oid > 0 else oid for oid, entry in self._live.items()}
        self._live = {new[oid]: entry for oid, entry in self._live.items()}
        self._row_ids = [new[oid] if oid else 0 for oid in self._row_ids]

    def assign(self, rows: Sequence[int], paths: Sequence[ClothoidPath]) -> None:
        """Rows ``rows`` take ``paths`` (:class:`ClothoidPath` objects, one each)."""
        for i, path in zip(rows, paths, strict=True):
            if self._row_ids[i] == id(path) and id(path) in self._live:
                continue
            self._release(i)
            got = self._live.get(id(path))
            if got is None:
                vec = fast_v1.flat_path(path)
                got = self._live[id(path)] = [path, *self._append(vec.shape[0]), 0]
                self.flat[got[1] : got[2]] = vec
            self._hold(i, id(path), got)

    def build(self, rows: Sequence[int], kinds: IntArray, params: Array) -> None:
        """Rows ``rows`` take the family paths of :func:`amigo_gym.paths.families.family_segments` (``kinds (m,)``,
        ``params (m, 3)``; the paths ``make_family_path`` builds with the default sample spacing), built in place in two
        compiled calls, one row each; ``ValueError`` naming a row whose parameters build no path."""
        kv, (nodes, run_nodes) = fast_v1.kernels(), fast_v1.node_tables()
        segs, lay = np.zeros((len(rows), 4 * FAMILY_SEGMENTS)), np.zeros((len(rows), 6))
        kv.family_rows(run_nodes, kinds, params, SAMPLE_SPACING, segs, lay)
        for j in np.flatnonzero(lay[:, 0] < 0.0).tolist():
            fam = SEGMENT_FAMILIES[int(kinds[j])]
            raise ValueError(f"PathArena.build: row {rows[j]}'s {fam} parameters {params[j].tolist()} build no path "
                             f"(make_family_path({fam!r}, ...) names the one out of range)")  # fmt: skip
        for i, size in zip(rows, (P_TAIL + 6 * lay[:, 1] + 2 * lay[:, 2]).astype(np.int64).tolist(), strict=True):
            self._release(i)
            self._key -= 1  # (path objects' keys are their ids, > 0)
            self._hold(i, self._key, self._live.setdefault(self._key, [None, *self._append(size), 0]))
        starts = self.starts[np.asarray(rows, dtype=np.intp)]
        loop("family_fill", self.parallel)(nodes, self.flat, starts, kinds, params, segs, lay)

    def _release(self, i: int) -> None:
        old = self._row_ids[i]
        if old:
            entry = self._live[old]
            entry[3] -= 1
            self._row_ids[i] = 0  # (a compaction before the row's new path is held skips the row)
            if entry[3] == 0:
                del self._live[old]
                self._dead += entry[2] - entry[1]

    def _hold(self, i: int, key: int, entry: list[Any]) -> None:
        entry[3] += 1
        self._row_ids[i] = key
        self.starts[i] = entry[1]
        self.stops[i] = entry[2]

    def rows_on(self, path: ClothoidPath) -> int:
        """How many rows hold ``path``."""
        entry = self._live.get(id(path))
        return 0 if entry is None else int(entry[3])

    def _append(self, length: int) -> tuple[int, int]:
        size = self.flat.shape[0]
        if self.used + length > size and 4 * (self.used - self._dead + length) <= 3 * size:
            self._compact()
        start = self.used
        stop = start + length
        if stop > size:
            grown = np.zeros(max(2 * size, stop))
            grown[:start] = self.flat[:start]
            self.flat = grown
        self.used = stop
        return start, stop

    def _compact(self) -> None:
        # in place, the live paths moved down in the order they lie: the array's pages stay mapped (a new array's
        # first touch page-faults on every append after it, most of a restart's cost in the arena)
        live = sorted(self._live.values(), key=lambda entry: entry[1])
        self.used = 0
        self._dead = 0
        for entry in live:
            start, stop = entry[1], entry[2]
            entry[1], entry[2] = self.used, self.used + stop - start
            self.flat[entry[1] : entry[2]] = self.flat[start:stop]  # (downwards: a source is never overwritten first)
            self.used = entry[2]
        for i, oid in enumerate(self._row_ids):
            if oid:
                entry = self._live[oid]
                self.starts[i] = entry[1]
                self.stops[i] = entry[2]


class BatchKernel:
    """The compiled step of ``n`` robots: constants :attr:`consts`, paths :attr:`arena`, the block :attr:`ws`
    ``(len(Rows._fields), n)`` (:attr:`rows` names its rows) and the episodes' keys :attr:`keys`; ``parallel`` runs
    the loops on numba's threads (the same results; :func:`amigo_gym.sim.fast_v1.wait_passively`)."""

    def __init__(self, k: tracking.Constants, n: int, parallel: bool = False) -> None:
        self._k = k
        self._row = fast_v1.StepKernel(k)
        self.consts: Array = self._row.consts
        self.parallel = parallel
        if parallel:
            fast_v1.wait_passively()
        self.arena = PathArena(n, parallel)
        self.ws: Array = np.zeros((len(layout_v1.Rows._fields), n))
        self.keys: NDArray[np.uint64] = np.zeros(n, dtype=np.uint64)
        self.ideal = k.params.ideal_actuators and self._row.n_normal == 0
        self._tans: Array = np.zeros((2, n if self.ideal else 0))
        self._restart: tuple[Any, ...] | None = None  # restart's path, template row and start
        self._bind()

    def _bind(self) -> None:
        # the loops for exactly the types of step's arguments (fast_v1.direct_call)
        self.rows = layout_v1.Rows(*self.ws)
        f1, f2, rings = np.zeros(1), np.zeros((1, 1)), np.zeros((1, 1, 2))
        i1, obs = np.zeros(1, dtype=np.int64), np.zeros((1, 1), dtype=np.float32)
        keys = np.zeros(1, dtype=np.uint64)
        par = self.parallel
        import numba  # (loaded with the kernels) tan and exp on numba's threads: this CPU's and threads' choice

        self._take = par and not (NUMPY_SIMD and numba.get_num_threads() < 8)
        args = (f1, f1, i1, i1, rings, f2, obs, 0, f1, f1, keys, f2, 0.0)
        self._step_rows: Any = fast_v1.direct_call(loop("step_rows", par), *args)
        if self.ideal:
            self._ideal_tangent_rows: Any = fast_v1.direct_call(
                loop("ideal_tangent_rows", par), f1, f2, f1, f1, f2, par
            )
            ideal = (f1, f1, i1, i1, f2, obs, f1, f1, f2, f2)
            self._ideal_rows: Any = fast_v1.direct_call(loop("ideal_rows", par), *ideal)
            self._record_rows: Any = fast_v1.direct_call(loop("record_rows", par), f2, 0.0, par)

    def __getstate__(self) -> dict[str, Any]:
        bound = ("rows", "_step_rows", "_ideal_tangent_rows", "_ideal_rows", "_record_rows", "_take")  # _bind's
        return {k: v for k, v in self.__dict__.items() if k not in bound}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind()

    def load(
        self, rows: Sequence[int], paths: Sequence[Any] | None, st: tracking.State, ep: tracking.Episode
    ) -> None:  # fmt: skip
        """Start the episodes of ``rows``: their paths (None: in the arena already), states and episodes (``(m,)``
        columns) into the block; ``TypeError`` for a path the compiled step does not run
        (:func:`amigo_gym.sim.fast_v1.compiled_path`)."""
        if paths is not None:
            for i, path in {id(q): (i, q) for i, q in zip(rows, paths, strict=True)}.values():  # each path once
                if not fast_v1.compiled_path(path, self._k.params):
                    raise TypeError(f"BatchKernel.load: row {i}'s path {type(path).__name__} is not compiled")
            self.arena.assign(rows, paths)
        r = np.asarray(rows, dtype=np.intp)
        fast_v1.load_rows(self.ws, r, st, ep, np.asarray(ep.l3) != self._k.l3)
        self.keys[r] = ep.key

    def start(
        self,
        rows: Sequence[int],
        paths: Sequence[Any] | None,
        st: tracking.State,
        ep: tracking.Episode,
        obs: NDArray[np.floating[Any]],
    ) -> Array:
        """:meth:`load` the rows and evaluate their start states (:func:`amigo_gym.task.v1.reset_columns`) into
        ``obs (len(rows), D)``; returns their info records ``(len(rows), RECORD_WIDTH)``, new."""
        self.load(rows, paths, st, ep)
        v_true, t = tracking.start_speed_time(st, ep)
        m = len(rows)
        rec = np.empty((m, layout_v1.RECORD_WIDTH))
        a = self.arena
        loop("start_rows", self.parallel)(
            self.consts, a.flat, a.starts, a.stops, self.ws, obs, rec, np.asarray(rows, dtype=np.int64),
            np.broadcast_to(np.asarray(v_true, dtype=np.float64), (m,)).copy(),
            np.broadcast_to(np.asarray(t, dtype=np.float64), (m,)).copy(), self._row.smooth_weight,
        )  # fmt: skip
        return rec

    def restart(
        self, rows: Sequence[int], path: Any, ep: tracking.Episode, u: Array, obs: NDArray[np.floating[Any]]
    ) -> Array:
        """:meth:`start` of ``rows`` on one fixed ``path`` with one episode ``ep`` (columns of one row) and the start
        draws ``u (m, 3)`` in [-1, 1] (:func:`amigo_gym.task.v1.start_state`'s ``u``), in one compiled call."""
        if self._restart is None or self._restart[0] is not path:  # the first row's column: the template
            zero = np.zeros(1)
            st = tracking.start_state(self._k, path, ep, (zero, zero, zero))
            self.load(rows[:1], [path], st, ep)
            q, p = path.pose_columns(zero), self._k.params
            v_a = tracking.start_speed_time(st, ep)[0]
            start = (q.x, q.y, q.theta, p.init_position_noise, p.init_heading_noise, v_a)
            self._restart = (path, self.ws[:, rows[0]].copy(), np.hstack(start).astype(np.float64))
        _, template, start = self._restart
        r = np.asarray(rows, dtype=np.int64)
        self.keys[r] = ep.key
        a = self.arena
        if a.rows_on(path) != len(a.starts):  # not every row on the path already
            a.assign(rows, [path] * len(rows))
        rec = np.empty((len(rows), layout_v1.RECORD_WIDTH))
        loop("restart_rows", self.parallel)(
            self.consts, a.flat, a.starts, a.stops, self.ws, obs, rec, r, template, start, u, self._row.smooth_weight
        )
        return rec

    def step(self, rings: Array, ring_step: int, a1: Array, a2: Array, obs: NDArray[np.floating[Any]]) -> Array:
        """Step every row (:func:`amigo_gym.task.v1.step_columns`) with the actions ``a1, a2 (n,)`` [-], the command
        rings ``rings (n, L, 2)`` [rad/s] (updated) and their counter ``ring_step``; the observations into
        ``obs (n, D)``. Returns every row's info record ``(n, RECORD_WIDTH)``, new: with ideal actuators and no draws
        the transpose of a field-major ``(RECORD_WIDTH, n)`` array (each entry's column contiguous), else C-ordered."""
        c, ws, a, sw = self.consts, self.ws, self.arena, self._row.smooth_weight
        if self.ideal and not self.rows.slip_max.any():  # no draws
            rec = np.empty((layout_v1.RECORD_WIDTH, ws.shape[1]))
            self._ideal_tangent_rows(c, ws, a1, a2, self._tans, self._take)
            if not self._take:  # numpy's tan and exp: SIMD where the CPU has AVX-512
                np.tan(self._tans, out=self._tans)
            self._ideal_rows(c, a.flat, a.starts, a.stops, ws, obs, a1, a2, self._tans, rec)
            exps = rec[layout_v1.R_TRACK : layout_v1.R_SMOOTH_EXP + 1]  # the three arguments' contiguous rows
            if not self._take:
                np.exp(exps, out=exps)
            self._record_rows(rec, sw, self._take)
            return rec.T
        rec = np.empty((ws.shape[1], layout_v1.RECORD_WIDTH))
        self._step_rows(c, a.flat, a.starts, a.stops, rings, ws, obs, ring_step, a1, a2, self.keys, rec, sw)
        return rec
