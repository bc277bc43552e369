"""What to tell the user about a result that needs a word (a network without curves)."""

from __future__ import annotations

__all__ = ["empty_network_hint"]


def empty_network_hint(net) -> str | None:
    """Why a network has no curves and what to change, in one line; None when it has curves.

    Parameters
    ----------
    net : CurveNetwork
        A reconstruction's result (``parameters["method"]`` names its method).

    Returns
    -------
    str or None
    """
    if net.n_curves:
        return None
    method = net.parameters.get("method")
    stats, prm = net.stats, net.parameters
    head = f"the network has no curves ({net.n_nodes} node(s))"
    if method == "paper":
        eps, tau = prm.get("epsilon"), prm.get("tau_s")
        if not stats.get("candidates"):
            return f"{head}: no point varies more than epsilon={eps:g} (eq. 2); lower --epsilon"
        return (f"{head}: the {stats['candidates']} candidate nodes were grouped into {stats.get('groups', 0)} "
                f"node(s) within tau_s={tau:g}; lower --tau-s, or raise --epsilon (now {eps:g}) to keep fewer "
                "candidates")
    if method == "robust":
        sp = prm.get("spacing")
        where = f"spacing {sp:g}" if isinstance(sp, (int, float)) else "the estimated spacing"
        return (f"{head}: no chain of points was long enough at {where}; give the sampling spacing "
                "with --spacing, or lower --param min_spur")
    return f"{head}; try another --method"
