"""A binary min-heap on two parallel arrays (keys, ids) for the kernels' Dijkstra runs."""

from __future__ import annotations


def _heap_pop(heap_k, heap_v, hs):  # pragma: no cover - compiled
    """Pop the smallest entry of the binary heap ``heap_k[:hs]`` / ``heap_v[:hs]`` (key, then
    id: equal keys come out by id, so the order never depends on the insertion order).

    Returns the key, the id and the new size."""
    key = heap_k[0]
    a = heap_v[0]
    hs -= 1
    if hs > 0:
        lk = heap_k[hs]
        lv = heap_v[hs]
        i = 0
        while True:
            c1 = 2 * i + 1
            if c1 >= hs:
                break
            c2 = c1 + 1
            if c2 < hs and (heap_k[c2] < heap_k[c1] or (heap_k[c2] == heap_k[c1] and heap_v[c2] < heap_v[c1])):
                c1 = c2
            if heap_k[c1] < lk or (heap_k[c1] == lk and heap_v[c1] < lv):
                heap_k[i] = heap_k[c1]
                heap_v[i] = heap_v[c1]
                i = c1
            else:
                break
        heap_k[i] = lk
        heap_v[i] = lv
    return key, a, hs


def _heap_push(heap_k, heap_v, hs, key, v):  # pragma: no cover - compiled
    """Push ``(key, v)`` on the binary heap of :func:`_heap_pop`; returns the new size."""
    i = hs
    hs += 1
    while i > 0:
        par = (i - 1) // 2
        if heap_k[par] > key or (heap_k[par] == key and heap_v[par] > v):
            heap_k[i] = heap_k[par]
            heap_v[i] = heap_v[par]
            i = par
        else:
            break
    heap_k[i] = key
    heap_v[i] = v
    return hs
