"""The examples that end each command's ``--help``, and the help formatter that keeps them."""

from __future__ import annotations

import argparse

__all__ = ["EXAMPLES", "HelpFormatter"]

#: Command -> the lines of its examples (each one runs as written from the repository's root).
EXAMPLES = {
    "reconstruct": [
        "curvenet reconstruct examples/mug.xyz -o mug.json --png mug.png",
        "curvenet reconstruct examples/mug.xyz -o mug.ply -o mug.svg --view iso --labels mug-labels.csv",
        "curvenet reconstruct examples/cube.xyz --method paper -o cube-paper.json",
        "cat examples/fig8_2d.xyz | curvenet reconstruct - --format xyz -o - --output-format geojson",
    ],
    "info": [
        "curvenet info examples/mug.xyz",
        "curvenet info scan.csv --columns x,y,z",
        "curvenet info mug.json",
    ],
    "formats": ["curvenet formats"],
    "render": [
        "curvenet render mug.json -o mug.png --points examples/mug.xyz",
        "curvenet render mug.json -o mug-side.png --elev 0 --azim 0",
    ],
    "view": [
        "curvenet view mug.json -o mug.html --points examples/mug.xyz",
        "curvenet view big.json -o big.html --max-points 50000",
    ],
    "bench": ["curvenet bench --quick", "curvenet bench --out docs"],
    "surface": [
        "curvenet surface mug.json -o mug-mesh.obj",
        "curvenet surface mug.json -o mug-mesh.ply --png mug-mesh.png",
    ],
    "completion": [
        'eval "$(curvenet completion bash)"',
        "curvenet completion zsh > ~/.zfunc/_curvenet",
    ],
}


def epilog(command: str) -> str | None:
    """The ``examples:`` block of a command's help, or None."""
    lines = EXAMPLES.get(command)
    return None if not lines else "examples:\n" + "\n".join("  " + s for s in lines)


class HelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, except that an ``examples:`` block keeps its lines."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        if text.startswith("examples:"):
            return "\n".join(indent + line for line in text.splitlines())
        return super()._fill_text(text, width, indent)
