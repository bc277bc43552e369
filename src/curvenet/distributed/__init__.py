"""Tiled, out-of-core reconstruction on Dask's distributed scheduler (extra ``dask``).

>>> from curvenet.distributed import reconstruct_tiled          # doctest: +SKIP
>>> net = reconstruct_tiled("scans/*.laz", tiles=100.0)         # doctest: +SKIP

The cloud is binned into the tiles of an explicit grid (:class:`TileGrid`), each tile is
reconstructed with a halo around it (:func:`halo_width`) by the default method with the whole
cloud's estimates, cut at its box into pieces and ports (:mod:`.cut`), and the pieces are
stitched across the faces (:mod:`.stitch`), their points left on disk (:mod:`.plan`):
:func:`tiled_network` gives the network so, to write it out without holding it. Dask is
imported only when a run starts.
"""

from .equality import network_difference
from .grid import TileGrid
from .halo import HALO_MARGIN, halo_width, interaction_reach
from .plan import StoredNetwork
from .run import make_client, reconstruct_tiled, tiled_network

__all__ = ["reconstruct_tiled", "tiled_network", "StoredNetwork", "make_client", "TileGrid", "halo_width", "interaction_reach", "HALO_MARGIN",
           "network_difference"]
