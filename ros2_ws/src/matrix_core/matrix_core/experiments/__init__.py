"""The paper's experiments on simulated MATRIX variants: a plan of cached steps, a runner and
the report writer of ``docs/RESULTS.md`` (``matrix-tracker experiments``). Pure Python, no rclpy."""
