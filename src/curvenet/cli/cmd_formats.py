"""``curvenet formats``: list readable and writable file formats."""

from __future__ import annotations

from .options import add_common


def register(sub) -> None:
    p = sub.add_parser("formats", help="list readable point formats and writable network formats")
    add_common(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..io import READERS, WRITERS

    print("Readable point files (by extension):")
    for ext, (_, desc) in sorted(READERS.items()):
        print(f"  {ext:<9} {desc}")
    print("Writable network files (by extension):")
    for ext, (_, desc) in sorted(WRITERS.items()):
        print(f"  {ext:<9} {desc}")
    print("Pictures (with the input points):")
    for ext, desc in PICTURES.items():
        print(f"  {ext:<9} {desc}")
    return 0


#: Picture outputs, which are not network writers (they take the input points too).
PICTURES = {
    ".png": "PNG picture: curvenet render, or reconstruct --png (extra viz)",
    ".html": "interactive viewer, one offline file: curvenet view, or reconstruct --html (extra viz)",
}
