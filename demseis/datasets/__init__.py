"""demseis.datasets: Zarr store, validation and the PyTorch Dataset."""
