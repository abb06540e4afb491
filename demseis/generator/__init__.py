"""demseis.generator: config, sampling, sweep and CLI."""
