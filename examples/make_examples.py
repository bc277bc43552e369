"""Regenerate the example point files shipped in this folder (deterministic).

    python examples/make_examples.py

- ``mug.xyz``: a mug-like wire model (analogue of the paper's Mug): rim and base loops, handle,
  junctions; sampled at spacing h/2 with Gaussian noise 0.1 h, in shuffled order.
- ``cube.xyz``: clean samples (no noise) along the twelve edges of a unit cube, the kind of
  input the paper's method is made for (``--method paper`` finds its 8 nodes and 12 curves).
- ``fig8_2d.xyz``: the 2D example in the spirit of the paper's Figure 8 (two curves close
  together), where the Euclidean minimum spanning tree goes wrong.
"""

from pathlib import Path

import numpy as np

from curvenet import synth

HERE = Path(__file__).resolve().parent


def main() -> None:
    mug = synth.model("mug")
    pts, _ = synth.sample(mug, h=synth.h_of(mug) / 2, noise=0.2, rng=7)
    np.savetxt(HERE / "mug.xyz", pts, fmt="%.6f", header="x y z  (curvenet example: mug wire model)")
    cube, _ = synth.sample(synth.model("cube"), rng=0)
    np.savetxt(HERE / "cube.xyz", cube, fmt="%.6f", header="x y z  (curvenet example: cube edges, clean)")
    fig8 = synth.model("fig8")
    pts, _ = synth.sample(fig8, noise=0.1, rng=8)
    np.savetxt(HERE / "fig8_2d.xyz", pts, fmt="%.6f", header="x y  (curvenet example: 2D, paper Figure 8)")


if __name__ == "__main__":
    main()
