"""demseis.labels: strain, fault/damage/layer labels and scoring."""
