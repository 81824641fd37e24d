"""Geometry layer: Christoffel symbols, connections in frames, Lie brackets, Frobenius."""
