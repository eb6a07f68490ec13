"""The DEM resolution study: what each DEM setting buys in accuracy and costs in time.

``grid`` expands the one-factor-at-a-time grid of the config's ``accuracy:``
block and writes each point's scene; ``analysis`` turns the runs into the cost
table and mu(I); ``figures`` draws them; ``python -m dem_study`` runs both.
``packing_cost`` is the packing's share of a campaign's DEM cost
(``python -m dem_study.packing_cost``); ``bulk*`` the bulk-against-walls study.
"""
from . import analysis, grid  # noqa: F401
