"""Pictures: floor plans, overlays on video, evaluation plots. Sinks only; no tracking state."""
