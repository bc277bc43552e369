"""The reconstruction methods, side by side.

- :mod:`.robust`: the parameter-free default (a package of stages around one topology object).
- :mod:`.paper`: the founding paper's method, faithfully (Algorithms 1 and 2).
- :mod:`.emst`: the Euclidean minimum spanning tree baseline (the paper's Figure 8).

Each exposes one ``reconstruct_*(points, **params) -> CurveNetwork``; :func:`curvenet.reconstruct`
picks one by name (:data:`curvenet.reconstruct.METHODS`).
"""
