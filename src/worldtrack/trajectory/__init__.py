"""Seed 002: trajectories across cameras that do not share views, by MAP estimation."""
