"""The sweep that writes a store: driver, per-run pipeline, workers, re-rendering, summaries."""
