"""demseis.dem: 2D discrete element model."""
