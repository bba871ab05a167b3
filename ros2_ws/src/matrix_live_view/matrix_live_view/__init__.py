"""The live view: the graph served over the Foxglove WebSocket protocol (Foxglove, Lichtblick)."""
