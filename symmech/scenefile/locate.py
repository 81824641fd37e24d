"""Finding the line of a key or an array element in a scene file's text (TOML parsers do
not report where a key is; see the package docstring)."""

from __future__ import annotations

import bisect
import string

# ---------------------------------------------------------------------------------------
# finding lines in the file text


_BARE_KEY_CHARACTERS = frozenset(string.ascii_letters + string.digits + "_-")
_ESCAPES = {"b": "\b", "t": "\t", "n": "\n", "f": "\f", "r": "\r", '"': '"', "\\": "\\"}


class _Scanner:
    """One pass over TOML text (that tomllib accepted), noting where things are.

    Linear time and no regular expression: each character is looked at a bounded number
    of times, whatever the file holds (a table header of 100 000 spaces costs what its
    length costs).  Notes the table headers ``(line, name, is_array)``, the keys of the
    statements ``key = value`` ``(line, position of their header or -1, key parts)`` (not
    the keys inside inline tables), and every string value ``(line, decoded value)``, the
    line being where its content starts (the line after an opening ``\"\"\"`` that ends its
    line, as TOML drops that line break).  Lines are 0-based.
    """

    def __init__(self, text: str):
        self.text = text
        self.i = 0
        self.line = 0
        self.headers: list[tuple[int, str, bool]] = []
        self.keys: list[tuple[int, int, tuple[str, ...]]] = []
        self.strings: list[tuple[int, str]] = []

    def run(self) -> _Scanner:
        text, n = self.text, len(self.text)
        depth = 0  # [ and { of values still open (a matrix over several lines)
        statement = True  # at the start of a statement: a header or a key
        while self.i < n:
            c = text[self.i]
            if c == "\n":
                self.line += 1
                self.i += 1
                statement = statement or depth == 0
            elif c in " \t\r":
                self.i += 1
            elif c == "#":
                end = text.find("\n", self.i)
                self.i = n if end < 0 else end
            elif statement and depth == 0:
                statement = False
                start = self.i
                if c == "[":
                    self._header()
                else:
                    self._statement_key()
                self.i = max(self.i, start + 1)
            elif c in "\"'":
                found = self._string()
                if found is not None:
                    self.strings.append(found)
            else:
                if c in "[{":
                    depth += 1
                elif c in "]}":
                    depth = max(0, depth - 1)
                self.i += 1
        return self

    def _header(self) -> None:
        line = self.line
        array = self.text.startswith("[[", self.i)
        self.i += 2 if array else 1
        parts = self._key_parts()
        closing = "]]" if array else "]"
        if parts is not None and self.text.startswith(closing, self.i):
            self.i += len(closing)
            self.headers.append((line, ".".join(parts), array))

    def _statement_key(self) -> None:
        line = self.line
        parts = self._key_parts()
        if parts is not None and self.text.startswith("=", self.i):
            self.i += 1
            self.keys.append((line, len(self.headers) - 1, tuple(parts)))

    def _skip_blanks(self) -> None:
        text, n = self.text, len(self.text)
        while self.i < n and text[self.i] in " \t":
            self.i += 1

    def _key_parts(self) -> list[str] | None:
        """A (dotted) key: bare or quoted parts separated by dots; None if there is none."""
        text, n = self.text, len(self.text)
        parts: list[str] = []
        while True:
            self._skip_blanks()
            if self.i >= n:
                return None
            c = text[self.i]
            if c in "\"'":
                if text.startswith(c * 3, self.i):
                    return None  # (a multi-line string is not a key)
                found = self._string()
                if found is None:
                    return None
                parts.append(found[1])
            else:
                j = self.i
                while j < n and text[j] in _BARE_KEY_CHARACTERS:
                    j += 1
                if j == self.i:
                    return None
                parts.append(text[self.i : j])
                self.i = j
            self._skip_blanks()
            if not self.text.startswith(".", self.i):
                return parts
            self.i += 1

    def _string(self) -> tuple[int, str] | None:
        """The string at ``self.i``: (line of its content, decoded value); None if broken."""
        text, n = self.text, len(self.text)
        quote = text[self.i]
        multi = text.startswith(quote * 3, self.i)
        self.i += 3 if multi else 1
        if multi and text.startswith(("\n", "\r\n"), self.i):
            self.i += 1 if text[self.i] == "\n" else 2
            self.line += 1
        content_line = self.line
        out: list[str] = []
        while self.i < n:
            c = text[self.i]
            if c == quote:
                run = 1
                if multi:
                    while run < 5 and text.startswith(quote, self.i + run):
                        run += 1
                    if run < 3:
                        out.append(quote * run)
                        self.i += run
                        continue
                out.append(quote * (run - 3 if multi else 0))
                self.i += run
                return content_line, "".join(out)
            if c == "\n" or (c == "\r" and text.startswith("\r\n", self.i)):
                if not multi:
                    return None
                self.i += 1 if c == "\n" else 2
                self.line += 1
                out.append("\n")
            elif c == "\\" and quote == '"':
                self._escape(out, multi)
            else:
                out.append(c)
                self.i += 1
        return None

    def _escape(self, out: list[str], multi: bool) -> None:
        text, n = self.text, len(self.text)
        nxt = text[self.i + 1 : self.i + 2]
        if multi and nxt in (" ", "\t", "\r", "\n"):
            # a line-ending backslash: the blanks and line breaks after it are dropped
            j = self.i + 1
            while j < n and text[j] in " \t\r\n":
                self.line += text[j] == "\n"
                j += 1
            self.i = j
        elif nxt in _ESCAPES:
            out.append(_ESCAPES[nxt])
            self.i += 2
        elif nxt in ("u", "U"):
            width = 4 if nxt == "u" else 8
            digits = text[self.i + 2 : self.i + 2 + width]
            if len(digits) == width and all(d in string.hexdigits for d in digits):
                code = int(digits, 16)
                if code <= 0x10FFFF:
                    out.append(chr(code))
            self.i += 2 + width
        else:
            out.append("\\")
            self.i += 1


class _Locator:
    """The lines of keys, tables and array elements of TOML text (see the module doc).

    Built from one linear :class:`_Scanner` pass; every query is a dictionary look-up or a
    binary search.  Regions: the top level runs from line 1 to the first table header; a
    table ``[name]`` (or the k-th ``[[name]]``) from its header to the next header.  All
    lines returned are 1-based.
    """

    def __init__(self, text: str):
        scan = _Scanner(text).run()
        self.headers = scan.headers
        self._header_lines = [line + 1 for line, _, _ in scan.headers]
        self._positions: dict[str, list[int]] = {}
        for pos, (_, name, _) in enumerate(scan.headers):
            self._positions.setdefault(name, []).append(pos)
        self._keys: dict[tuple[int, tuple[str, ...]], int] = {}
        for line, pos, parts in scan.keys:
            # a dotted key a.b.c = 1 is also where a and a.b are first written
            for k in range(1, len(parts) + 1):
                self._keys.setdefault((pos, parts[:k]), line + 1)
        self._strings: dict[str, list[int]] = {}
        for line, value in scan.strings:
            self._strings.setdefault(value, []).append(line + 1)

    def _header(self, table: str, index: int = 0) -> int | None:
        positions = self._positions.get(table, ())
        return positions[index] if index < len(positions) else None

    def table(self, table: str, index: int = 0) -> int | None:
        """1-based line of the header of ``table`` (the ``index``-th for arrays)."""
        pos = self._header(table, index)
        return None if pos is None else self._header_lines[pos]

    def key(self, table: str | None, key: str, index: int = 0) -> int | None:
        """1-based line of ``key =`` in ``table`` (None: top level), else of the table.

        A dotted key is found too: ``value`` of table ``parameters.m`` is ``m.value =`` in
        ``[parameters]`` or ``parameters.m.value =`` at the top level.
        """
        if table is None:
            return self._keys.get((-1, (key,)))
        pos = self._header(table, index)
        if pos is not None and (pos, (key,)) in self._keys:
            return self._keys[pos, (key,)]
        if index == 0:
            parts = tuple(table.split("."))
            for cut in range(len(parts) - 1, -1, -1):
                outer = -1 if cut == 0 else self._header(".".join(parts[:cut]))
                found = self._keys.get((outer, (*parts[cut:], key))) if outer is not None else None
                if found is not None:
                    return found
        return None if pos is None else self._header_lines[pos]

    def element(self, start: int | None, value: object) -> int | None:
        """1-based line where the string ``value`` starts, on or after line ``start`` and
        before the next table header; else ``start``."""
        if start is None or not isinstance(value, str) or not value:
            return start
        lines = self._strings.get(value)
        if not lines:
            return start
        k = bisect.bisect_left(lines, start)
        if k == len(lines):
            return start
        h = bisect.bisect_right(self._header_lines, start)
        if h < len(self._header_lines) and self._header_lines[h] <= lines[k]:
            return start
        return lines[k]
