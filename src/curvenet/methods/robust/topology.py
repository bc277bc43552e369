"""The topology of a network in the making: regions, chains and which chain end sits at which region.

:class:`Topology` is the one owner of that bookkeeping. The repairs (:mod:`.repairs`) and the
node placement (:mod:`.nodes`) read it and change it only through its methods, which keep
three things consistent: every live open chain's end is listed at its region
(:meth:`Topology.incident`), the valence of every region (:attr:`Topology.v`, the number of
live open chain ends there), and the points of each region. :meth:`Topology.check` verifies
them; it runs after every change when ``CURVENET_CHECK_TOPOLOGY=1`` (the test suite sets it).
"""

from __future__ import annotations

import itertools
import os

import numpy as np

from .chains import Chain, order_between
from .thresholds import LAYOUT

__all__ = ["Topology", "TopologyError"]

_EMPTY = np.zeros(0, dtype=np.int64)


class TopologyError(AssertionError):
    """An invariant of :class:`Topology` does not hold (a bug in a repair, never bad input)."""


def _checking() -> bool:
    return os.environ.get("CURVENET_CHECK_TOPOLOGY", "") in ("1", "true", "yes")


class Topology:
    """Regions (point sets around junctions and free ends) joined by chains.

    Parameters
    ----------
    P : (N, d) ndarray
        The points (a region's points are ordered along a curve when it is joined through).
    chains : list of Chain
        Ordered chains with the regions of their ends (-1: none). The topology takes them
        over: their ``ends`` change only through it.
    regions : list of (m,) ndarray of int64
        The points of each region.

    Notes
    -----
    An open chain end without a region gets an empty region of its own (a free end). A chain
    end is listed at its region in the order the ends arrived there (that order reaches the
    node placement, so the methods below keep it exactly). Entries of dead chains may stay in
    those lists; :meth:`incident` filters them.
    """

    def __init__(self, P: np.ndarray, chains: list[Chain], regions: list[np.ndarray]):
        self.P = P
        self.chains: list[Chain] = list(chains)
        self.regions: list[np.ndarray] = list(regions)
        for c in self.chains:  # dangling open ends -> empty free-end regions
            if c.closed:
                continue
            for s in (0, 1):
                if c.ends[s] < 0:
                    self.regions.append(np.zeros(0, dtype=np.int64))
                    c.ends[s] = len(self.regions) - 1
        self.alive: list[bool] = [True] * len(self.chains)
        self._ends_at: list[list[tuple[int, int]]] = [[] for _ in self.regions]
        for i, c in enumerate(self.chains):
            if not c.closed:
                for s in (0, 1):
                    self._ends_at[c.ends[s]].append((i, s))
        self.v: np.ndarray = self.valence()
        self._changed()

    # ------------------------------------------------------------------------------ reading
    def valence(self) -> np.ndarray:
        """The number of live open chain ends at every region, counted afresh.

        Returns
        -------
        (n_regions,) ndarray of int64
        """
        e = [c.ends for c, a in zip(self.chains, self.alive) if a and not c.closed]
        e = np.fromiter(itertools.chain.from_iterable(e), dtype=np.int64, count=2 * len(e))
        return np.bincount(e, minlength=len(self.regions)).astype(np.int64)

    def incident(self, r: int) -> list[tuple[int, int]]:
        """The live chain ends ``(chain, side)`` at region ``r``, in the order they arrived."""
        return [(i, s) for i, s in self._ends_at[r] if self.alive[i] and self.chains[i].ends[s] == r]

    def listed(self, r: int) -> bool:
        """True when any chain end, live or dead, was ever left listed at region ``r``."""
        return bool(self._ends_at[r])

    def end_ids(self, i: int, s: int) -> np.ndarray:
        """The ids of chain ``i`` running towards its end ``s``."""
        c = self.chains[i]
        return c.ids if s == 1 else c.ids[::-1]

    def live(self) -> list[Chain]:
        """The live chains, in order."""
        return [c for i, c in enumerate(self.chains) if self.alive[i]]

    def owners(self) -> tuple[np.ndarray, np.ndarray]:
        """The live chain of every point (N,) (-1: none) and the point's place in that chain (N,)."""
        owner = np.full(len(self.P), -1, dtype=np.int64)
        place = np.zeros(len(self.P), dtype=np.int64)
        for i, c in enumerate(self.chains):
            if self.alive[i]:
                owner[c.ids] = i
                place[c.ids] = np.arange(len(c.ids))
        return owner, place

    # ------------------------------------------------------------------------------ changes
    def absorb(self, r: int, t: int) -> None:
        """Merge region ``r`` into region ``t``: its points, the live chain ends at it, its valence.

        Raises
        ------
        TopologyError
            ``r == t`` (a region merged into itself: a bug in the caller).
        """
        if r == t:
            raise TopologyError(f"region {r} cannot be merged into itself")
        self.regions[t] = np.r_[self.regions[t], self.regions[r]]
        self.regions[r] = np.zeros(0, dtype=np.int64)
        for i, s in self._ends_at[r]:
            if self.alive[i] and self.chains[i].ends[s] == r:
                self.chains[i].ends[s] = t
                self._ends_at[t].append((i, s))
        self._ends_at[r] = []
        self.v[t] += self.v[r]
        self.v[r] = 0
        self._changed()

    def absorb_chain(self, i: int, r: int) -> None:
        """Chain ``i`` dies and its points join region ``r`` (it lay inside that junction)."""
        self.drop(i)
        self.regions[r] = np.r_[self.regions[r], self.chains[i].ids].astype(np.int64)
        self._changed()

    def release(self, r: int) -> np.ndarray:
        """Region ``r`` gives up its points (returned; the caller gives them to a chain) and
        stays, without points, with its chain ends and valence."""
        ids, self.regions[r] = self.regions[r], np.zeros(0, dtype=np.int64)
        self._changed()
        return ids

    def trim_end(self, i: int, s: int, k: int) -> None:
        """The ``k`` points of chain ``i`` at its side ``s`` (0: its start) join the region that
        end is at (a chain that ran on past its node); the chain keeps at least one point."""
        c = self.chains[i]
        k = min(k, len(c.ids) - 1)
        if k <= 0:
            return
        if s == 1:
            moved, c.ids = c.ids[len(c.ids) - k:], c.ids[:len(c.ids) - k].copy()
        else:
            moved, c.ids = c.ids[:k], c.ids[k:].copy()
        r = c.ends[s]
        self.regions[r] = np.r_[self.regions[r], moved].astype(np.int64)
        self._changed()

    def extend_end(self, i: int, s: int, ids: np.ndarray) -> None:
        """The points ``ids`` of the region at end ``s`` of chain ``i`` (ordered from that end
        outwards, into the region) join the chain at that end; the chain's end stays at the
        region (a chain end read short of its junction)."""
        c = self.chains[i]
        ids = np.asarray(ids, dtype=np.int64)
        c.ids = np.r_[c.ids, ids] if s == 1 else np.r_[ids[::-1], c.ids]
        r = c.ends[s]
        self.regions[r] = self.regions[r][~np.isin(self.regions[r], ids)]
        self._changed()

    def drop(self, i: int) -> None:
        """Chain ``i`` dies (its ends leave the valence of their regions)."""
        c = self.chains[i]
        self.alive[i] = False
        if not c.closed:
            self.v[c.ends[0]] -= 1
            self.v[c.ends[1]] -= 1
        self._changed()

    def merge_twin(self, i: int, j: int) -> None:
        """Chains ``i`` and ``j``, between the same two regions, become one: ``j`` dies and its
        points join ``i``, each placed along ``i`` by its projection on ``i``'s polyline
        (ties: ``i``'s own points first, then by point id)."""
        ci, cj = self.chains[i], self.chains[j]
        Q = self.P[ci.ids]
        seg = np.diff(Q, axis=0)
        s0 = np.r_[0.0, np.cumsum(np.linalg.norm(seg, axis=1))]
        X = self.P[cj.ids]
        par = np.zeros(len(X))
        if len(Q) >= 2:
            # every point against every segment of i: the nearest one; in blocks of points so
            # that the (points, segments, d) temporaries hold about LAYOUT.curve_block
            # point-segment pairs (a long curve traced twice), the same arithmetic per pair
            L2 = np.maximum(np.einsum("ij,ij->i", seg, seg), np.finfo(float).tiny)
            rows = max(1, LAYOUT.curve_block // len(seg))
            for a in range(0, len(X), rows):
                Xb = X[a:a + rows, None, :]
                t = np.clip(np.einsum("kij,ij->ki", Xb - Q[None, :-1, :], seg) / L2, 0.0, 1.0)
                foot = Q[None, :-1, :] + t[..., None] * seg[None]
                k = np.argmin(np.einsum("kij,kij->ki", Xb - foot, Xb - foot), axis=1)
                par[a:a + rows] = s0[k] + t[np.arange(len(k)), k] * np.sqrt(L2[k])
        ids = np.r_[ci.ids, cj.ids]
        key = np.r_[s0, par]
        own = np.r_[np.zeros(len(ci.ids)), np.ones(len(cj.ids))]
        self.chains[i] = Chain(ids[np.lexsort((ids, own, key))], list(ci.ends))
        self.drop(j)

    def join_through(self, r: int, inc: list[tuple[int, int]]) -> None:
        """The two chain ends ``inc`` at region ``r`` (valence 2) become one curve through it.

        Two chains become one (the second dies); one chain whose two ends meet there becomes
        a closed loop. The region's points, ordered from one end to the other, join the curve
        and the region is emptied.
        """
        (i, si), (j, sj) = inc
        ci = self.chains[i]
        a_ids = ci.ids if si == 1 else ci.ids[::-1]
        a_other = ci.ends[1 - si]
        P = self.P
        if i == j:
            mid = order_between(P, self.regions[r], P[a_ids[-1]], P[a_ids[0]])
            self.chains[i] = Chain(np.r_[a_ids, mid], [-1, -1], closed=True)
            self.regions[r] = np.zeros(0, dtype=np.int64)
            self.v[r] -= 2
            self._changed()
            return
        cj = self.chains[j]
        b_ids = cj.ids if sj == 0 else cj.ids[::-1]
        b_other = cj.ends[1 - sj]
        mid = order_between(P, self.regions[r], P[a_ids[-1]], P[b_ids[0]])
        self.chains[i] = Chain(np.r_[a_ids, mid, b_ids], [a_other, b_other])
        self.alive[j] = False
        self.regions[r] = np.zeros(0, dtype=np.int64)
        ea = self._ends_at
        ea[r] = []
        ea[a_other] = [e for e in ea[a_other] if e != (i, 1 - si)] + [(i, 0)]
        ea[b_other] = [e for e in ea[b_other] if e != (j, 1 - sj)] + [(i, 1)]
        self.v[r] -= 2
        self._changed()

    def split_chain(self, j: int, lo: int, hi: int, i: int, s: int) -> np.ndarray:
        """A free end joins chain ``j`` in its middle: a new junction region there.

        The points ``lo:hi`` of chain ``j`` and the free end's region (that of end ``s`` of
        chain ``i``) form the new region; chain ``j`` is split into the part before and the
        part after (a closed chain is opened there instead).

        Returns
        -------
        (hi - lo,) ndarray of int64
            The chain points that became region points.
        """
        r = self.chains[i].ends[s]
        cj = self.chains[j]
        core = cj.ids[lo:hi]
        self.regions.append(np.r_[core, self.regions[r]].astype(np.int64))
        nr = len(self.regions) - 1
        ea = self._ends_at
        ea.append([(i, s)])
        self.regions[r] = np.zeros(0, dtype=np.int64)
        ea[r] = []
        self.chains[i].ends[s] = nr
        self.v[r] = 0
        self.v = np.r_[self.v, 1]
        if cj.closed:
            self.chains[j] = Chain(np.r_[cj.ids[hi:], cj.ids[:lo]], [nr, nr])
            ea[nr] += [(j, 0), (j, 1)]
        else:
            self._split_open(j, lo, hi, nr)
        self.v[nr] += 2
        self._changed()
        return core

    def cross(self, r: int, j: int, lo: int, hi: int) -> None:
        """The open chain ``j`` crosses region ``r`` in its middle (``0 < lo < hi < len``): its
        points ``lo:hi`` join the region, and it is split into the part before (chain ``j``) and
        the part after (a new chain), both ending at ``r``. The region's valence grows by 2."""
        self.regions[r] = np.r_[self.regions[r], self.chains[j].ids[lo:hi]].astype(np.int64)
        self._split_open(j, lo, hi, r)
        self.v[r] += 2
        self._changed()

    def _split_open(self, j: int, lo: int, hi: int, r: int) -> None:
        """The open chain ``j`` without its points ``lo:hi``: the part before (chain ``j``) and
        the part after (a new chain), both ending at region ``r`` (its valence left to the
        caller)."""
        cj = self.chains[j]
        a, b = cj.ends
        self.chains[j] = Chain(cj.ids[:lo], [a, r])
        self.chains.append(Chain(cj.ids[hi:], [r, b]))
        self.alive.append(True)
        jn = len(self.chains) - 1
        ea = self._ends_at
        ea[b] = [(jn, 1) if e_ == (j, 1) else e_ for e_ in ea[b]]  # (before r's: b may be r)
        ea[r] += [(j, 1), (jn, 0)]

    def split_region(self, r: int, ends_b: list[tuple[int, int]], ids_a: np.ndarray, ids_b: np.ndarray,
                     seg: np.ndarray) -> int:
        """Region ``r`` becomes two junctions joined by a new chain (two junctions seen as one).

        Parameters
        ----------
        r : int
            The region; it keeps the points ``ids_a`` and the chain ends not in ``ends_b``.
        ends_b : list of (int, int)
            The live chain ends ``(chain, side)`` at ``r`` that move to the new region.
        ids_a, ids_b : ndarray of int64
            The points of ``r`` and of the new region.
        seg : (n,) ndarray of int64
            The points of the new chain, ordered from ``r`` to the new region (n >= 1).

        Returns
        -------
        int
            The new region.
        """
        self.regions[r] = np.asarray(ids_a, dtype=np.int64)
        self.regions.append(np.asarray(ids_b, dtype=np.int64))
        nr = len(self.regions) - 1
        ea = self._ends_at
        moved = set(ends_b)
        ea[r] = [e for e in ea[r] if e not in moved]
        ea.append([e for e in ends_b])
        for i, s in ends_b:
            self.chains[i].ends[s] = nr
        self.v[r] -= len(ends_b)
        self.v = np.r_[self.v, len(ends_b)]
        self.join_regions(r, nr, seg)
        return nr

    def join_regions(self, a: int, b: int, seg: np.ndarray) -> int:
        """A new chain of the points ``seg`` (ordered from region ``a`` to region ``b``, n >= 1)
        between the two regions (a cell's side inside a region split into its junctions).

        Returns
        -------
        int
            The new chain.
        """
        self.chains.append(Chain(np.asarray(seg, dtype=np.int64), [a, b]))
        self.alive.append(True)
        j = len(self.chains) - 1
        self._ends_at[a].append((j, 0))
        self._ends_at[b].append((j, 1))
        self.v[a] += 1
        self.v[b] += 1
        self._changed()
        return j

    def free_branch(self, r: int, ids: np.ndarray) -> int:
        """A new chain of the points ``ids`` (ordered from region ``r`` outwards, n >= 1, none of
        them a region's) from ``r`` to a new empty free-end region (a free branch that lay
        inside the region).

        Returns
        -------
        int
            The new chain.
        """
        return self.join_regions(r, self._free_end_region(), ids)

    def _free_end_region(self) -> int:
        """A new empty free-end region, no chain end at it yet; its index."""
        self.regions.append(np.zeros(0, dtype=np.int64))
        self._ends_at.append([])
        self.v = np.r_[self.v, 0]
        return len(self.regions) - 1

    def branch_chain(self, i: int, core: np.ndarray, arms: list[np.ndarray], far: list[int]) -> int:
        """Open chain ``i`` branches at a junction: it dies, the points ``core`` become a new
        region, and each branch of ``arms`` (ids ordered from the junction outwards) a chain
        from it to region ``far[k]`` (-1: a new empty free-end region); the one-junction case of
        :meth:`branch_chain_cores`.

        Returns
        -------
        int
            The new region.
        """
        nr = len(self.regions)
        self.branch_chain_cores(i, [core], [(ids, 0, f) for ids, f in zip(arms, far)])
        return nr

    def branch_chain_cores(self, i: int, cores: list[np.ndarray], pieces: list[tuple[np.ndarray, int, int]]) -> None:
        """Open chain ``i`` branches at several junctions: it dies, each of ``cores`` (point ids)
        becomes a new region, and each piece ``(ids, a, f)`` a chain from core ``a`` (an index
        into ``cores``; ``ids`` ordered from it) to ``f``: a region (>= 0), a new empty free-end
        region (-1), or core ``-f - 2``."""
        self.drop(i)
        ea = self._ends_at
        first = len(self.regions)
        for core in cores:
            self.regions.append(np.asarray(core, dtype=np.int64))
            ea.append([])
        self.v = np.r_[self.v, np.zeros(len(cores), dtype=self.v.dtype)]
        for ids, a, f in pieces:
            na = first + a
            if f == -1:
                f = self._free_end_region()
            elif f < -1:
                f = first + (-f - 2)
            self.join_regions(na, f, ids)
        self._changed()

    # ------------------------------------------------------------------------------ checks
    def check(self) -> None:
        """Raise :class:`TopologyError` unless the invariants hold.

        Every live open chain has two ends at existing regions and is listed at both; the
        valence is that of the live open chains; no point lies on two live chains.
        """
        n = len(self.regions)
        if not (len(self.alive) == len(self.chains) and len(self._ends_at) == n == len(self.v)):
            raise TopologyError("regions, chains and their lists differ in length")
        for i, c in enumerate(self.chains):
            if not self.alive[i] or c.closed:
                continue
            for s in (0, 1):
                r = c.ends[s]
                if not 0 <= r < n:
                    raise TopologyError(f"chain {i} end {s} at region {r} of {n}")
                if (i, s) not in self._ends_at[r]:
                    raise TopologyError(f"chain {i} end {s} is not listed at its region {r}")
        if not np.array_equal(self.v, self.valence()):
            raise TopologyError("the valence kept differs from the valence counted")
        ids = [c.ids for i, c in enumerate(self.chains) if self.alive[i]]
        if ids:
            flat = np.concatenate(ids)
            if len(np.unique(flat)) != len(flat):
                raise TopologyError("a point lies on two live chains")

    def _changed(self) -> None:
        if _checking():
            self.check()
