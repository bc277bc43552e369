"""Pictures of curve networks (extra ``viz``).

Modules here import matplotlib or plotly only inside their functions, so importing
:mod:`curvenet.plots` costs nothing. See :mod:`curvenet.plots.network_png` for PNG pictures and
:mod:`curvenet.viewer` for the interactive HTML viewer.
"""
