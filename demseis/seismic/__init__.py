"""demseis.seismic: properties, rasterisation, impedance, reflectivity, wavelets, noise."""
