"""The scene file reader, part 1: the declarations (header, coordinates, parameters,
functions, inputs, frame)."""

from __future__ import annotations

import sympy as sp

from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.scenefile.format import (
    _FRAME_KEYS,
    _FUNCTION_KEYS,
    _IDENTIFIER,
    _MAX_IDENTIFIER,
    _PARAMETER_KEYS,
    FORMAT_VERSION,
    MAX_NAMES,
    SIGNS,
    _clip,
    _did_you_mean,
    _short,
    _toml_type,
)
from symmech.scenefile.reader_base import _LoaderBase


class _NamesLoader(_LoaderBase):
    """The declarations of a scene file: header, coordinates, parameters, functions, inputs
    and the frame (each refused name is recorded and stops the expressions being read)."""

    def header(self) -> tuple[str, str]:
        data = self.data
        if "format" in data:
            fmt = data["format"]
            if isinstance(fmt, bool) or fmt != FORMAT_VERSION:
                self.fail(
                    f"unsupported format {_short(fmt, 60)}; this symmech reads format"
                    f" {FORMAT_VERSION}",
                    "format",
                    self.line(None, "format"),
                    _clip(fmt),
                )
        name = data.get("name", self.default_name)
        if not isinstance(name, str) or not _IDENTIFIER.match(name) or len(name) > 64:
            self.fail(
                f"the scene name must be an identifier of at most {_MAX_IDENTIFIER} characters"
                f" (letters, digits, _; it names generated code), got {_short(name)}",
                "name",
                self.line(None, "name"),
                str(name)[:40],
            )
            name = self.default_name
        description = data.get("description", "")
        if not isinstance(description, str):
            self.fail(
                f"expected a string, got {_toml_type(description)}",
                "description",
                self.line(None, "description"),
            )
            description = ""
        return name, description

    def coordinates(self) -> list[sp.Symbol]:
        line = self.line(None, "coordinates")
        if "coordinates" not in self.data:
            self.fail("required key 'coordinates' is missing", "coordinates", None)
            self.names_refused = True
            return []
        names = self.string_list(self.data["coordinates"], "coordinates", line)
        if names is None:
            return []
        if not names:
            self.fail("a scene needs at least one coordinate", "coordinates", line)
            self.names_refused = True
        if len(names) > MAX_NAMES:
            self.fail(f"{len(names)} coordinates (limit {MAX_NAMES})", "coordinates", line)
            self.names_refused = True
            return []
        q = []
        for i, nm in enumerate(names):
            ok = self.name_ok(nm, f"coordinates[{i}]", self.loc.element(line, nm), "coordinate")
            if ok is not None:
                q.append(sp.Symbol(ok, real=True))
        for s in q:
            vel = velocity_of(s)
            if vel.name in self.reserved:
                self.fail(
                    f"the velocity '{vel.name}' of coordinate '{s.name}' is also declared as"
                    f" {self.reserved[vel.name]}",
                    "coordinates",
                    line,
                    vel.name,
                )
                self.names_refused = True
            self.reserved[vel.name] = f"the velocity of coordinate '{s.name}'"
        self.table.update({s.name: s for s in q})
        self.table.update({velocity_of(s).name: velocity_of(s) for s in q})
        return q

    def parameters(self) -> tuple[list[sp.Symbol], dict[sp.Symbol, sp.Expr]]:
        raw = self.data.get("parameters", {})
        if not isinstance(raw, dict):
            self.fail(
                f"expected a table [parameters], got {_toml_type(raw)}",
                "parameters",
                self.line(None, "parameters"),
            )
            self.names_refused = True
            return [], {}
        if len(raw) > MAX_NAMES:
            self.fail(
                f"{len(raw)} parameters (limit {MAX_NAMES})",
                "parameters",
                self.loc.table("parameters"),
            )
            self.names_refused = True
            return [], {}
        params: list[sp.Symbol] = []
        defaults: dict[sp.Symbol, sp.Expr] = {}
        for key, spec in raw.items():
            field_name = f"parameters.{_clip(key)}"
            line = self.entry_line("parameters", key)
            name = self.name_ok(key, field_name, line, "parameter")
            if isinstance(spec, dict):
                keys = self.sub_key_args("parameters", key, line)
                self.check_keys(spec, _PARAMETER_KEYS, field_name, **keys)
                line = self.line(keys["table"], "value") or line
                value = spec.get("value")
                sign = spec.get("sign", "positive")
                if "description" in spec and not isinstance(spec["description"], str):
                    self.fail("expected a string", f"{field_name}.description", line)
            else:
                value, sign = spec, "positive"
            if not isinstance(sign, str) or sign not in SIGNS:
                self.fail(
                    f"sign must be one of {', '.join(SIGNS)}, got {_short(sign, 60)}"
                    f"{_did_you_mean(str(sign), list(SIGNS))}",
                    f"{field_name}.sign",
                    line,
                    _clip(sign),
                )
                sign = "positive"
            if name is None:
                continue
            symbol = sp.Symbol(name, **SIGNS[sign])
            params.append(symbol)
            if value is not None:
                number = self.default_value(value, symbol, sign, f"{field_name}.value", line)
                if number is not None:
                    defaults[symbol] = number
        self.table.update({p.name: p for p in params})
        return params, defaults

    def default_value(
        self, value: object, symbol: sp.Symbol, sign: str, field: str, line: int | None
    ) -> sp.Expr | None:
        number = self.expression(value, field, line, {})
        if number is None:
            return None
        if not number.is_number or not number.is_real:
            self.fail(
                f"default value {_clip(number)} is not a real number", field, line, _clip(value)
            )
            return None
        test = {
            "positive": number.is_positive,
            "nonnegative": number.is_nonnegative,
            "negative": number.is_negative,
            "nonpositive": number.is_nonpositive,
            "nonzero": number.is_nonzero,
        }.get(sign, True)
        if not test:
            self.fail(
                f"default value {number} of '{symbol.name}' is not {sign}"
                " (parameters are positive unless 'sign' says otherwise)",
                field,
                line,
                _clip(value),
            )
            return None
        return number

    def functions(self) -> dict[str, sp.Expr]:
        raw = self.data.get("functions", {})
        if not isinstance(raw, dict):
            self.fail(
                f"expected a table [functions], got {_toml_type(raw)}",
                "functions",
                self.line(None, "functions"),
            )
            self.names_refused = True
            return {}
        raw = {**raw, **self.inputs(raw)}
        if len(raw) > MAX_NAMES:
            self.fail(
                f"{len(raw)} functions (limit {MAX_NAMES})",
                "functions",
                self.loc.table("functions"),
            )
            self.names_refused = True
            return {}
        # the definitions may use t and the parameters only
        allowed = {k: v for k, v in self.table.items() if k == "t" or v not in self.coord_like}
        out: dict[str, sp.Expr] = {}
        # a refused function still gets a place-holder f(t) in the symbol table: the
        # expressions that use it are read as usual, and report their own problems only
        stand_in: dict[str, sp.Expr] = {}
        for key, spec in raw.items():
            field_name = f"functions.{_clip(key)}"
            line = self.entry_line("functions", key)
            name = self.name_ok(key, field_name, line, "function")
            expression: object = None
            arguments: object = None
            real = True
            if isinstance(spec, dict):
                keys = self.sub_key_args("functions", key, line)
                self.check_keys(spec, _FUNCTION_KEYS, field_name, **keys)
                expression = spec.get("expression")
                arguments = spec.get("arguments")
                real = spec.get("real", True)
                if not isinstance(real, bool):
                    self.fail("'real' must be true or false", f"{field_name}.real", line)
                    real = True
                if "description" in spec and not isinstance(spec["description"], str):
                    self.fail("expected a string", f"{field_name}.description", line)
            elif isinstance(spec, str | int | float) and not isinstance(spec, bool):
                expression = spec
            else:
                self.fail(
                    "expected an expression string in t (a defined function) or a table"
                    f" ({{}} for an arbitrary function), got {_toml_type(spec)}",
                    field_name,
                    line,
                )
                spec = None
            if name is None:
                continue
            value: sp.Expr | None = None
            if spec is None:
                pass
            elif expression is not None and arguments is not None:
                self.fail(
                    "give 'expression' (a defined function of t) or 'arguments' (an arbitrary"
                    " function of them), not both",
                    f"{field_name}.arguments",
                    line,
                )
            elif expression is not None:
                value = self.expression(expression, field_name, line, allowed)
            else:
                args = self.function_arguments(arguments, f"{field_name}.arguments", line)
                if args is not None:
                    fn = sp.Function(name, real=True) if real else sp.Function(name)
                    value = fn(*args)
            if value is None:
                stand_in[name] = sp.Function(name, real=True)(TIME)
            else:
                out[name] = value
        self.function_names = frozenset(raw)
        self.table.update(stand_in)
        self.table.update(out)
        return out

    def inputs(self, functions: dict) -> dict[str, dict]:
        """``[inputs]``: run-time inputs, each an arbitrary real function of t (``tau = {}``
        or ``tau = { description = "..." }``), read as ``[functions]`` entries ``{}``."""
        raw = self.data.get("inputs", {})
        if not isinstance(raw, dict):
            self.fail(
                f"expected a table [inputs], got {_toml_type(raw)}",
                "inputs",
                self.line(None, "inputs"),
            )
            self.names_refused = True
            return {}
        out: dict[str, dict] = {}
        for key, spec in raw.items():
            field_name = f"inputs.{_clip(key)}"
            line = self.entry_line("inputs", key)
            if key in functions:
                self.fail(
                    "declared both in [functions] and in [inputs]", field_name, line, _clip(key)
                )
                self.names_refused = True
                continue
            if not isinstance(spec, dict) or set(spec) - {"description"}:
                self.fail(
                    'an input is a table {} or { description = "..." } (a function of t given'
                    " at run time)",
                    field_name,
                    line,
                )
                self.names_refused = True
                continue
            out[key] = dict(spec)
        return out

    def function_arguments(
        self, raw: object, field: str, line: int | None
    ) -> list[sp.Symbol] | None:
        """The arguments of an arbitrary function: distinct names among t and the
        coordinates (default: t alone)."""
        if raw is None:
            return [TIME]
        coordinates = {s.name: s for s in self.q}
        allowed = ["t", *coordinates]
        if not isinstance(raw, list) or not raw or not all(isinstance(a, str) for a in raw):
            self.fail(
                f"expected a non-empty array of argument names (among {', '.join(allowed)}),"
                f" got {_toml_type(raw)} {_short(raw, 60)}",
                field,
                line,
            )
            return None
        args: list[sp.Symbol] = []
        for a in raw:
            if a not in allowed:
                self.fail(
                    f"'{_clip(a)}' is not t or a coordinate: an arbitrary function's arguments"
                    f" are among {', '.join(allowed)}{_did_you_mean(a, allowed)}",
                    field,
                    self.loc.element(line, a),
                    _clip(a),
                )
                return None
            arg = TIME if a == "t" else coordinates[a]
            if arg in args:
                self.fail(f"argument '{a}' is repeated", field, self.loc.element(line, a), a)
                return None
            args.append(arg)
        return args

    def frame(self, q: list[sp.Symbol]) -> tuple[sp.Matrix | None, list[sp.Symbol] | None]:
        raw = self.data.get("frame")
        if raw is None:
            return None, None
        fline = self.loc.table("frame") or self.line(None, "frame")
        if not isinstance(raw, dict):
            self.fail(f"expected a table [frame], got {_toml_type(raw)}", "frame", fline)
            return None, None
        self.check_keys(raw, _FRAME_KEYS, "frame", "frame")
        vline = self.line("frame", "quasi_velocities")
        if "quasi_velocities" in raw:
            names = self.string_list(raw["quasi_velocities"], "frame.quasi_velocities", vline)
        else:
            self.fail(
                "required key 'quasi_velocities' (the names of v, q_dot = S v) is missing",
                "frame.quasi_velocities",
                fline,
            )
            self.names_refused = True
            names = None
        n = len(q)
        v: list[sp.Symbol] = []
        if names is not None:
            if len(names) != n:
                self.fail(
                    f"expected {n} quasi-velocities (one per coordinate), got {len(names)}",
                    "frame.quasi_velocities",
                    vline,
                )
                self.names_refused = True
            for i, nm in enumerate(names):
                ok = self.name_ok(
                    nm,
                    f"frame.quasi_velocities[{i}]",
                    self.loc.element(vline, nm),
                    "quasi-velocity",
                )
                if ok is not None:
                    v.append(sp.Symbol(ok, real=True))
        has_matrix, has_inverse = "matrix" in raw, "inverse" in raw
        if has_matrix == has_inverse:
            self.fail(
                "give exactly one of 'matrix' (S, q_dot = S v) and 'inverse' (S^-1, v = S^-1"
                " q_dot)",
                "frame",
                fline,
            )
            return None, None
        key = "matrix" if has_matrix else "inverse"
        # the frame depends on the coordinates and parameters only
        table = {k: e for k, e in self.table.items() if e not in self.velocity_like}
        M = self.matrix(raw[key], n, f"frame.{key}", self.line("frame", key), table, False)
        if M is None or len(v) != n:
            return None, None
        if has_inverse:
            try:
                if M.det() == 0:
                    raise ValueError("det == 0")
                M = sp.simplify(M.inv())
            except (ValueError, ZeroDivisionError):  # sympy's NonInvertibleMatrixError
                self.fail(
                    "the matrix S^-1 is singular (determinant 0); it has no inverse S",
                    "frame.inverse",
                    self.line("frame", key),
                )
                return None, None
        self.table.update({s.name: s for s in v})
        return M, v
