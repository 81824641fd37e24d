"""LaTeX text-mode escaping, shared by every rich display (scenes, impact maps, Carnot
results) and by ``symmech show --latex``."""

from __future__ import annotations

__all__ = ["latex_text"]

#: LaTeX text-mode escapes (``^``, ``~``, ``<`` and ``>`` are not plain characters there
#: either: with the default font encoding ``<`` prints as an inverted exclamation mark).
_LATEX_SPECIALS = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
    "<": r"\textless{}",
    ">": r"\textgreater{}",
}


def latex_text(text: str) -> str:
    """``text`` with each LaTeX special character escaped once, for ``\\text{}`` or a
    section title.

    >>> latex_text("wall rough_wall, 100%")
    'wall rough\\\\_wall, 100\\\\%'
    """
    return "".join(_LATEX_SPECIALS.get(c, c) for c in text)
