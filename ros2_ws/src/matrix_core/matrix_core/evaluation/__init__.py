"""Scoring what the live node graph published against ground truth (used by the demo monitor)."""
