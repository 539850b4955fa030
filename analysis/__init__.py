"""Reproductions of the paper's quantitative results (``nemesys analyze``, ``nemesys results``).

Numpy and matplotlib are used here freely: this runs on the surface, never on the vehicle.
"""
