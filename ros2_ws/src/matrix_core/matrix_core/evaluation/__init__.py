"""Scoring what the live node graph published against ground truth: per frame while it runs (``graph_report``,
used by the graph monitor) and afterwards from a recording (``recording``, ``matrix-tracker
evaluate-recording``)."""
