"""demseis.learning: the learning side of the product. A U-Net trained on stores
(:mod:`demseis.learning.train`: the shared fixed-budget loop, mixes of stores, prediction of
sections), and the model a user trains, saves and applies (:mod:`demseis.learning.model`:
``demseis train``, ``demseis predict``). Both need torch (the ``[torch]`` extra) and import it
inside their functions, so this package imports without it.

Scoring of predictions is :mod:`demseis.evaluation`, which this package uses.
"""
