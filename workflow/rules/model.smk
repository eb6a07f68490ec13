# The continuum model against the DEM.


def model_targets():
    return []
