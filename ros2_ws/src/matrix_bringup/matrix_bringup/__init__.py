"""Launch files and the graph monitor of matrix-tracker."""
