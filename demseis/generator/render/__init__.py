"""A run's states imaged and labelled into samples (``section``); survey sampling (``survey``)."""
