"""Constraints layer: gradients, Gram matrix, projectors, multipliers (Carnot paper §2.2)."""
