"""The halo: how far around its box a tile must see so that it decides as the whole cloud.

Every decision of the default method about a point looks at most a fixed number of local
spacings ``h`` away (plus a multiple of the noise): the junction shell, the links, the walks
that place a junction node, the repairs' reaches. A tile that sees its box widened by that
reach, with the whole cloud's :class:`~curvenet.methods.robust.Estimates`, reconstructs the
part of the network inside its box as one process would (what lies farther out is cut at the
halo's edge: a false free end, which the tile does not keep).
"""

from __future__ import annotations

from ..methods.robust import Estimates
from ..methods.robust.thresholds import DEFAULTS, LINKS, NODES, NOISE, REPAIRS, SHELL, SPACING, SPANNING

__all__ = ["HALO_MARGIN", "interaction_reach", "halo_width"]

#: The halo is this many times the method's largest reach at the median spacing: the local
#: spacing of a sparse stretch is above the median (twice it at the density ratio 3 of the
#: benchmark), and every radius is in local spacings.
HALO_MARGIN: float = 2.0


def interaction_reach() -> tuple[float, float]:
    """The method's largest interaction radius: ``(in spacings, in noise scales)``.

    The candidates, from :mod:`curvenet.methods.robust.thresholds`: the walk into a junction
    (``NODES.walk_far`` spacings, the largest), the chain trim at a node (twice
    ``NODES.span``), the outer shell, the directional links, the junction merge
    (``REPAIRS.merge_len``), the test that drops the points alone in space
    (``SPACING.isolated`` median spacings, :func:`curvenet.methods.robust.frames.isolated`),
    the spanning tree read around a region (``SPANNING.margin``);
    the walk's shell radii widen by ``SHELL.widen`` noise scales per shell radius, so its noise
    term is ``walk_far / shell_outer * shell_outer * widen``.

    The radii in local spacings are covered at up to ``HALO_MARGIN`` median spacings. Points
    alone in space, whose spacing would be tens of median spacings (outliers), are dropped
    first by a test that looks ``SPACING.isolated`` median spacings far; the halo holds that
    test for every point within the largest radius of the box
    (``HALO_MARGIN * in_h >= in_h + SPACING.isolated``, tested). A kept point of a larger
    spacing still reaches farther (a clump of outliers, a stretch sampled more than
    ``HALO_MARGIN`` times sparser than the median): there a tile can decide otherwise.

    Returns
    -------
    in_h : float
        In local spacings.
    in_noise : float
        In noise scales (``NOISE.scale`` times the noise std).
    """
    in_h = max(NODES.walk_far, 2 * NODES.span, DEFAULTS.shell_outer, DEFAULTS.link * LINKS.directional,
               REPAIRS.merge_len, SPACING.isolated, SPANNING.margin)
    in_noise = max(NODES.walk_far * SHELL.widen, NODES.fit_noise, LINKS.strip_noise, LINKS.gap_noise)
    return float(in_h), float(in_noise)


def halo_width(estimates: Estimates) -> float:
    """The halo, in input units, for a cloud of these whole-cloud estimates.

    Parameters
    ----------
    estimates : Estimates
        The median spacing and noise std of the whole input.

    Returns
    -------
    float
        ``HALO_MARGIN * (in_h * hmed + in_noise * NOISE.scale * sigma)`` (see
        :func:`interaction_reach`).
    """
    in_h, in_noise = interaction_reach()
    return float(HALO_MARGIN * (in_h * estimates.hmed + in_noise * NOISE.scale * estimates.sigma))
