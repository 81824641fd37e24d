"""Escaping text for the languages of generated files: one function per target, one place.

Every string of a scene that reaches generated text (the scene's, walls', coordinates',
parameters' and functions' names, expressions printed in comments, descriptions, the
"left out" notes) goes through exactly one of these functions, applied by the templates as
Jinja filters (registered by :func:`symmech.codegen.backends.environment`) or by the code
that builds a file name:

``c_comment``         text inside a C block comment ``/* ... */``
``c_string``          the contents of a C string literal ``"..."``
``python_docstring``  text inside a Python triple-quoted (non-raw) docstring ``\"\"\"...\"\"\"``
``python_comment``    text after ``#`` in Python
``file_name``         a file-name stem (and C / Python identifier part) from a name
``terminal``          text printed on a terminal (the command line's stderr and stdout)

The rules, each a property the tests check on hostile strings:

* *One line.*  Every run of whitespace, including the line breaks that only some tools
  honour (``\\r``, ``\\v``, ``\\f``, ``\\x1c``-``\\x1f``, ``\\x85``, U+2028, U+2029), becomes one
  space: text can never end a ``#`` comment or start a new line of code.
* *Visible, not raw.*  Any other character that is not printable (``str.isprintable``:
  control characters such as NUL, format characters such as the bidirectional overrides
  U+202E, U+2066-U+2069 of "Trojan source", surrogates, unassigned code points) is written
  as its escape ``\\xNN``, ``\\uNNNN`` or ``\\UNNNNNNNN``, as ``repr`` would; a backslash of
  the text is written ``\\\\`` so the rendering is unambiguous.
* *C comments.*  ``*/`` (the end of the comment) becomes ``* /`` and ``/*`` (a nested
  opening, ``-Wcomment``) ``/ *``; ``??`` becomes ``? ?`` (with ``-std=c99`` the trigraph
  ``??/`` is a backslash, which at the end of a line splices the next line into this one);
  the text never starts with ``/`` nor ends with ``*`` or a backslash (so it cannot complete
  a ``*/`` with the template text around it, nor splice lines).
* *C strings.*  Only printable ASCII other than ``\\``, ``"`` and ``?`` is kept; every other
  byte of the UTF-8 encoding is an octal escape ``\\ooo`` (at most three digits, so a
  following digit is never absorbed, unlike ``\\x``).
* *Python docstrings.*  ``"`` becomes ``\\"`` (so neither ``\"\"\"`` nor a quote just
  before the closing ``\"\"\"`` can end the string early) and backslashes are doubled (no
  escape sequence of the text is interpreted: ``\\N{...}`` or ``\\x`` cannot make the file
  unimportable).
* *Terminal.*  Every character that is not printable, except a newline, is written as its
  ``repr`` escape, so an escape sequence (``\x1b[...``), a carriage return or a bell in a
  file or scene name cannot move the cursor, recolour or retitle the terminal; backslashes
  are left as they are (this text is only read, never parsed).
* *File names.*  Only ``[0-9A-Za-z_]`` (runs of others become one ``_``), never empty,
  never starting with a digit, never ``.``/``..``, and at most :data:`MAX_STEM` characters:
  a longer name is cut and ends with 12 hexadecimal digits of the SHA-256 of the full name
  (so two long names that differ only at the end still give different files).
"""

from __future__ import annotations

import hashlib
import re

__all__ = [
    "MAX_STEM",
    "c_comment",
    "c_string",
    "file_name",
    "one_line",
    "python_comment",
    "python_docstring",
    "terminal",
]

#: Longest file-name stem :func:`file_name` returns (a file system allows 255 bytes per
#: name; generated files add a prefix and suffixes such as ``_<hash>.py``).
MAX_STEM = 80


def one_line(text: object) -> str:
    """``text`` as one line: runs of whitespace (any Unicode line or paragraph separator
    included) become one space, leading and trailing whitespace is dropped, and every
    other non-printable character is written as its ``repr`` escape (``\\x00``,
    ``\\u202e``); a backslash of the text is doubled first, so escapes stay unambiguous."""
    words = str(text).replace("\\", "\\\\").split()
    out = []
    for ch in " ".join(words):
        if ch == " " or ch.isprintable():
            out.append(ch)
        else:
            out.append(repr(ch)[1:-1])
    return "".join(out)


def c_comment(text: object) -> str:
    """``text`` safe inside a C block comment (module docstring: one line, visible escapes,
    no ``*/``, ``/*`` or ``??``, no ``/`` first and no ``*`` or backslash last)."""
    s = one_line(text)
    while True:
        t = s.replace("*/", "* /").replace("/*", "/ *").replace("??", "? ?")
        if t == s:
            break
        s = t
    if s.startswith("/"):
        s = " " + s
    if s.endswith(("*", "\\")):
        s += " ."
    return s


def c_string(text: object) -> str:
    """The contents of a C string literal with the value ``text`` (UTF-8): printable ASCII
    except ``\\``, ``"`` and ``?`` as is, every other byte as an octal escape."""
    out = []
    for byte in str(text).encode("utf-8", "surrogatepass"):
        ch = chr(byte)
        if 0x20 <= byte < 0x7F and ch not in '\\"?':
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return "".join(out)


def python_docstring(text: object) -> str:
    """``text`` safe inside a non-raw Python triple-quoted string: one line, visible
    escapes, backslashes doubled, ``"`` escaped as ``\\"``."""
    return one_line(text).replace("\\", "\\\\").replace('"', '\\"')


def python_comment(text: object) -> str:
    """``text`` safe after ``#`` in Python: one line with visible escapes (nothing else
    can end a comment)."""
    return one_line(text)


def terminal(text: object) -> str:
    """``text`` safe to print on a terminal (module docstring): non-printable characters
    other than a newline as ``repr`` escapes."""
    return "".join(
        ch if ch == "\n" or ch == " " or ch.isprintable() else repr(ch)[1:-1] for ch in str(text)
    )


def file_name(name: object, *, limit: int = MAX_STEM) -> str:
    """A file-name stem (also a valid C and Python identifier) for ``name`` (module
    docstring): ``[0-9A-Za-z_]`` only, no leading digit, at most ``limit`` characters, a
    hash of the full name ending a shortened one."""
    full = str(name)
    base = re.sub(r"[^0-9A-Za-z_]+", "_", full)
    base = re.sub(r"_+", "_", base).strip("_") or "s"
    if base[0].isdigit():
        base = f"s_{base}"
    if len(base) > limit:
        digest = hashlib.sha256(full.encode("utf-8", "surrogatepass")).hexdigest()[:12]
        base = f"{base[: limit - 13].rstrip('_')}_{digest}"
    return base
