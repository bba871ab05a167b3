"""The paper's experiments (issue 8) on simulated MATRIX variants: a plan of cached steps, a runner and
the report writer of ``docs/RESULTS.md`` (``matrix-tracker experiments``). Pure Python, no rclpy."""
