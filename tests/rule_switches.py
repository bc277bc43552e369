"""Switches that turn one rule of the robust method off, for the tests of an older repair whose
sampling a newer rule now handles first: they measure the older repair alone."""

from curvenet.methods.robust import frames, thresholds


def without_vote_keep(monkeypatch):
    """Every tangent at odds with a coherent vote is replaced, as before the rule that keeps a
    tangent its own two nearest samples confirm (:func:`.frames.vote_tangents`): no neighbour
    lies within a cosine over 1 of it."""
    off = thresholds.TANGENTS._replace(vote_keep_cos=1.0 + thresholds.NUMERIC.rel)
    monkeypatch.setattr(frames, "TANGENTS", off)


def without_twin_pieces(monkeypatch):
    """Two pieces of a split chain into one region are never two curves, as before the rule
    that reads them as a double edge (:func:`.branched._pieces_apart`): no point of one lies
    over an infinite distance from the other."""
    from curvenet.methods.robust import branched

    monkeypatch.setattr(branched, "BRANCHED", thresholds.BRANCHED._replace(twin_apart=float("inf")))


def without_skew_pairs(monkeypatch):
    """Strokes crossing a curve through two junction points, not parallel, are always one
    junction drawn loosely in :func:`.paired.best_pairs`, as before it read two branches whose
    lines pass apart (skew teeth of a comb) as two junctions (:func:`.paired.meet_loosely`)."""
    from curvenet.methods.robust import paired

    monkeypatch.setattr(paired, "meet_loosely", lambda *a: True)


def without_junction_crossings(monkeypatch):
    """Only regions of valence 2 are crossed by a chain passing through them
    (:func:`.repairs.cross_pass_regions`), as before it read a junction's region passed by a
    chain as a crossing too (:func:`.repairs._may_cross`)."""
    from curvenet.methods.robust import repairs

    monkeypatch.setattr(repairs, "_may_cross", lambda topo, r, c, far: topo.v[r] == 2)
