"""Declaration layer: symbols, safe expressions, walls, and the validated scene declaration."""
