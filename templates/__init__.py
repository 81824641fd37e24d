"""Code templates of symmech (Jinja), shipped in the wheel as ``symmech.templates``.

This file only makes the folder importable as a package, so ``importlib.resources`` finds
the templates both in an installed wheel and in an editable checkout.
"""
