"""The one strict reader of every file a user gives: tables, calibrations, feet, plans, timelines.

:func:`read_data` (JSON, TOML, YAML) and :func:`read_text` (any other, a CSV) refuse, in one
line naming the file (a :class:`~.exceptions.SourceError`, ``parameter`` the kind of file):
anything but a regular file (unread), more than ``max_bytes`` (counted while reading), bad
UTF-8; duplicate keys, YAML tags (``!!python/object``), JSON's ``NaN``; more than
:data:`MAX_ALIASES` YAML aliases, :data:`MAX_DEPTH` levels or ``max_values`` values after
alias expansion (a "billion laughs" in milliseconds); keys that are not strings, integers of
more than 15 digits, strings of more than :data:`MAX_STRING` characters. Values are then
checked by :func:`number` / :func:`numbers`, :func:`text` / :func:`texts`,
:func:`check_keys`, :func:`named` (the file named in a value's error) and :func:`csv_table`.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from numbers import Real
from pathlib import Path
from typing import Any

from ._io import read_regular
from .exceptions import (
    HexapodKinError,
    OptionalDependencyError,
    ParameterError,
    SourceError,
    did_you_mean,
)

__all__ = ["FORMATS", "MAX_ALIASES", "MAX_BYTES", "MAX_DEPTH", "MAX_STRING", "MAX_VALUES",
           "check_keys", "clip", "csv_table", "named", "number", "numbers", "parse_data",
           "read_data", "read_text", "text", "texts"]  # fmt: skip

#: Formats of :func:`read_data`, by file suffix.
FORMATS = {".json": "json", ".toml": "toml", ".yaml": "yaml", ".yml": "yaml"}
#: Default byte cap of a user file.
MAX_BYTES = 1_000_000
#: Deepest nesting of values (a real file is far inside it).
MAX_DEPTH = 16
#: Most values of a file after YAML alias expansion (default of ``max_values``).
MAX_VALUES = 100_000
#: Most YAML aliases of a file.
MAX_ALIASES = 64
#: Most characters of one string.
MAX_STRING = 10_000
_MAX_INT = 2**53
_DECIMAL = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")
_EXPONENT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")


def _refuse(name: str, what: str, problem: str, allowed: str) -> SourceError:
    message = f"{what}={name!r}: {problem}; allowed: {allowed}"
    return SourceError(message, parameter=what, value=name, allowed=allowed)


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 160 else text[:157] + "..."


def _invalid(name: str, what: str, fmt: str, exc: BaseException) -> SourceError:
    return SourceError(
        f"{what}={name!r}: not valid {fmt} ({_short(exc)})", parameter=what, value=name
    )


def read_text(
    path: str | os.PathLike[str],
    what: str = "source",
    max_bytes: int = MAX_BYTES,
    too_big: type[HexapodKinError] | None = None,
) -> str:
    """The UTF-8 text of the regular file ``path`` (at most ``max_bytes``; else ``too_big``).

    Raises:
        SourceError: Not a regular file, unreadable, too large or not UTF-8.

    """
    data = read_regular(path, max_bytes, what, too_big)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        problem = f"not UTF-8 text (byte {exc.start}: {exc.reason})"
        raise _refuse(str(path), what, problem, "UTF-8 text") from None


def read_data(
    path: str | os.PathLike[str],
    what: str = "source",
    *,
    fmt: str | None = None,
    max_bytes: int = MAX_BYTES,
    mapping: str | None = None,
) -> Any:
    """The values of a JSON, TOML or YAML file, read strictly (see the module docstring).

    ``what``: the kind of file (``parameter``); ``fmt``: ``"json"``, ``"toml"`` or ``"yaml"``
    (default by suffix, else YAML); ``mapping``: the file must hold a mapping of these keys.

    Raises:
        SourceError: Any refusal of the module docstring, or a syntax error.
        OptionalDependencyError: YAML without PyYAML, TOML on Python 3.10 without tomli.

    """
    fmt = fmt or FORMATS.get(Path(path).suffix.lower(), "yaml")
    data = parse_data(read_text(path, what, max_bytes), str(path), fmt, what)
    if mapping is not None and not isinstance(data, dict):
        problem = f"the file must hold a mapping ({mapping}), not a {type(data).__name__}"
        raise _refuse(str(path), what, problem, "a mapping")
    return data


def parse_data(
    text: str, name: str, fmt: str, what: str = "source", max_values: int = MAX_VALUES
) -> Any:
    """The values of ``text`` in ``fmt`` (``json``, ``toml``, ``yaml``), checked as a file's."""
    try:
        if fmt == "json":
            data = _json(text, name, what)
        elif fmt == "toml":
            try:
                import tomllib as toml  # type: ignore[import-not-found,unused-ignore]
            except ModuleNotFoundError:  # pragma: no cover - Python 3.10
                try:
                    import tomli as toml  # type: ignore[no-redef,import-not-found,unused-ignore]
                except ModuleNotFoundError:
                    raise OptionalDependencyError(
                        "reading TOML on Python 3.10 needs tomli; `pip install tomli`",
                        parameter=what,
                    ) from None
            try:
                data = toml.loads(text)
            except toml.TOMLDecodeError as exc:
                raise _invalid(name, what, "TOML", exc) from None
        else:
            data = _yaml(text, name, what)
    except RecursionError:
        raise _refuse(name, what, f"values nested too deeply for the {fmt.upper()} reader",
                      f"nesting up to {MAX_DEPTH} levels") from None  # fmt: skip
    except ValueError as exc:  # e.g. an integer beyond Python's digit limit
        if isinstance(exc, HexapodKinError):  # the package's own errors are ValueErrors
            raise
        digits = re.search(r"value has (\d+) digits", str(exc))
        problem = (
            f"an integer of {digits.group(1)} digits" if digits
            else f"a value the {fmt.upper()} reader refuses ({_short(exc)})"
        )  # fmt: skip
        raise _refuse(name, what, problem, "integers of at most 15 digits") from None
    # deep, huge (after alias expansion) or odd values refused; iterative, stops early
    stack: list[tuple[Any, int, str]] = [(data, 0, "")]
    count = 0
    while stack:
        value, depth, key = stack.pop()
        count += 1
        if count > max_values:
            raise _refuse(name, what, f"more than {max_values} values (after alias expansion)",
                          f"at most {max_values} values")  # fmt: skip
        if depth > MAX_DEPTH:
            raise _refuse(name, what, f"values nested deeper than {MAX_DEPTH} levels",
                          f"nesting up to {MAX_DEPTH} levels")  # fmt: skip
        where = f"key {key!r}" if key else "a value"
        if isinstance(value, dict):
            for k, v in value.items():
                if not isinstance(k, str):
                    raise _refuse(name, what, f"the key {clip(k)} is not a string",
                                  "keys that are strings")  # fmt: skip
                stack.append((k, depth + 1, key))
                stack.append((v, depth + 1, k[:40]))
        elif isinstance(value, (list, tuple)):
            stack.extend((v, depth + 1, key) for v in value)
        elif isinstance(value, bool) or value is None:
            continue
        elif isinstance(value, int):
            if abs(value) > _MAX_INT:
                raise _refuse(name, what, f"{where}: an integer of {len(str(abs(value)))} digits",
                              "integers of at most 15 digits")  # fmt: skip
        elif isinstance(value, str):
            if len(value) > MAX_STRING:
                raise _refuse(name, what, f"{where}: a string of {len(value)} characters",
                              f"strings of at most {MAX_STRING} characters")  # fmt: skip
        elif not isinstance(value, float):
            raise _refuse(name, what, f"{where}: a value of type {type(value).__name__}",
                          "numbers, strings, lists and mappings")  # fmt: skip
    return data


def _json(text: str, name: str, what: str) -> Any:
    def pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key, value in items:
            if key in out:
                raise _refuse(name, what, f"key {clip(key)} given twice",
                              "each key once per mapping")  # fmt: skip
            out[key] = value
        return out

    def constant(word: str) -> Any:
        raise _refuse(name, what, f"{word} is not a JSON number", "finite numbers")

    try:
        return json.loads(text, object_pairs_hook=pairs, parse_constant=constant)
    except json.JSONDecodeError as exc:
        raise _invalid(name, what, "JSON", exc) from None


def _yaml(text: str, name: str, what: str) -> Any:
    """PyYAML's safe loader refusing duplicate keys, deep nesting, many aliases and tags."""
    try:
        import yaml
    except ModuleNotFoundError:  # pragma: no cover - pyyaml ships with the test extra
        raise OptionalDependencyError(
            "reading YAML files needs PyYAML; `pip install hexapod-kin[tables]`", parameter=what
        ) from None

    class Loader(yaml.SafeLoader):  # type: ignore[name-defined,unused-ignore]
        depth = 0
        aliases = 0

        def compose_node(self, parent: Any, index: Any) -> Any:
            if self.check_event(yaml.AliasEvent):
                self.aliases += 1
                if self.aliases > MAX_ALIASES:
                    raise _refuse(name, what, f"more than {MAX_ALIASES} YAML aliases",
                                  f"at most {MAX_ALIASES} aliases")  # fmt: skip
                return super().compose_node(parent, index)
            self.depth += 1
            if self.depth > MAX_DEPTH:
                raise _refuse(name, what, f"values nested deeper than {MAX_DEPTH} levels",
                              f"nesting up to {MAX_DEPTH} levels")  # fmt: skip
            try:
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

        def construct_mapping(self, node: Any, deep: bool = False) -> Any:
            seen: set[Any] = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    dup = key in seen
                    seen.add(key)
                except TypeError:  # an unhashable key: the base class refuses it
                    continue
                if dup:
                    line = key_node.start_mark.line + 1
                    raise _refuse(name, what, f"key {clip(key)} given twice (line {line})",
                                  "each key once per mapping")  # fmt: skip
            return super().construct_mapping(node, deep=deep)

    # YAML 1.2 floats: PyYAML (YAML 1.1) reads 1e-3 or 1.5e3 as text (its exponent needs a sign)
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT, list("-+0123456789."))
    loader = Loader(text)
    try:
        return loader.get_single_data()
    except yaml.constructor.ConstructorError as exc:  # a tag such as !!python/object
        found = re.search(r"tag '([^']*)'", str(exc.problem))
        if found is None:
            raise _invalid(name, what, "YAML", exc) from None
        tag = found.group(1).replace("tag:yaml.org,2002:", "!!")
        mark = exc.problem_mark
        where = f"line {mark.line + 1}: " if mark is not None else ""
        allowed = "plain YAML values (numbers, strings, lists, mappings)"
        raise _refuse(
            name, what, f"{where}the YAML tag {clip(tag)} is not allowed", allowed
        ) from None
    except yaml.YAMLError as exc:
        raise _invalid(name, what, "YAML", exc) from None
    finally:
        loader.dispose()


def clip(value: Any) -> str:
    """``repr(value)``, shortened past 40 characters (a value quoted in a message)."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:20]}...({len(text)} characters)"


# ---------------------------------------------------------------- the values of a file
def _wrong(where: str, value: Any, problem: str, allowed: str, parameter: str | None) -> Exception:
    shown = clip(value)
    return ParameterError(f"{where}={shown}{problem}", parameter=parameter or where, value=shown,
                          allowed=allowed)  # fmt: skip


def number(value: Any, where: str, *, parameter: str | None = None) -> float:
    """``value`` as a finite float: an int or float of a file (``'0.3'``, ``true``: typos).

    Raises:
        ParameterError: ``"<where>=<value> is not a finite number"``; ``parameter``
            defaults to ``where``.

    """
    if isinstance(value, Real) and not isinstance(value, bool):  # numpy's bool_ is not Real
        try:
            x = float(value)
        except OverflowError:
            x = math.inf
        if math.isfinite(x):
            return x
    raise _wrong(where, value, " is not a finite number", "a finite number", parameter)


def numbers(value: Any, where: str, n: int | None = None, *, parameter: str | None = None) -> Any:
    """Nested lists of finite numbers (each as :func:`number`, named ``where[3][1]``), as floats.

    With ``n``, ``value`` must be a flat list of ``n`` numbers.

    Raises:
        ParameterError: Not a list (of ``n``), or a value that is not a finite number.

    """
    if not isinstance(value, list | tuple) or (n is not None and len(value) != n):
        shape = f"a list of {n} numbers" if n is not None else "a list of numbers"
        raise _wrong(where, value, f": {shape} is required", shape, parameter)
    return [
        numbers(v, f"{where}[{i}]", parameter=parameter or where)
        if isinstance(v, list | tuple) and n is None
        else number(v, f"{where}[{i}]", parameter=parameter or where)
        for i, v in enumerate(value)
    ]


def text(value: Any, where: str, *, parameter: str | None = None) -> str:
    """A name or text of a file: a string (never ``5`` or ``true``: "must be a string")."""
    if not isinstance(value, str):
        raise _wrong(where, value, " must be a string (quote it)", "a string", parameter)
    return value


def texts(value: Any, where: str, *, parameter: str | None = None) -> tuple[str, ...]:
    """A list of names, each a string (:func:`text`, its index named)."""
    if not isinstance(value, list | tuple):
        problem = ": a list of names (strings) is required"
        raise _wrong(where, value, problem, "a list of strings", parameter)
    return tuple(
        text(v, f"{where}[{i}]", parameter=parameter or where) for i, v in enumerate(value)
    )


def check_keys(
    got: Iterable[Any], allowed: Sequence[str], where: str, *, parameter: str | None = None
) -> None:
    """Refuse a key not in ``allowed``: ``"<where>: unknown key 'x' (did you mean ...)"``."""
    for key in got:
        if key not in allowed:
            raise ParameterError(
                f"{where}: unknown key {clip(key)}{did_you_mean(str(key), allowed)}; "
                f"allowed: {list(allowed)}",
                parameter=parameter or str(key),
                value=clip(key),
                allowed=list(allowed),
            )


@contextmanager
def named(
    path: str | os.PathLike[str], what: str, error: type[HexapodKinError] | None = None
) -> Iterator[None]:
    """A :class:`~.exceptions.ParameterError` raised inside, again as ``what='path': <error>``.

    Raised as ``error`` when given (e.g. :class:`SourceError`); the reader's own refusals
    (:class:`SourceError`) already name the file and pass.
    """
    try:
        yield
    except ParameterError as exc:
        raise (error or type(exc))(
            f"{what}={str(path)!r}: {exc}",
            parameter=exc.parameter,
            value=exc.value,
            allowed=exc.allowed,
        ) from None


# ---------------------------------------------------------------- CSV
def csv_table(
    text: str, name: str, what: str
) -> tuple[dict[str, str], list[str], list[list[float]]]:
    """A CSV's ``# key: value`` lines, its header's cells and its rows of numbers.

    After the header (the first line not blank nor ``#``), rows of as many plain finite
    decimals (``-1.5``, ``.25``, ``3e-4``; not ``inf``, ``nan``, ``1_000``). ``name``: the file;
    ``what``: the kind of file.

    Raises:
        SourceError: No header, a row of another width, or a cell that is not a finite
            decimal number (``"<file>: line L, column C (<name>): '<value>' ..."``).

    """
    meta: dict[str, str] = {}
    header: list[str] | None = None
    rows: list[list[float]] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        if line.startswith("#"):
            key, _, value = line[1:].partition(":")
            meta[key.strip()] = value.strip()
            continue
        if not line.strip():
            continue
        cells = line.split(",")
        if header is None:
            header = [c.strip() for c in cells]
            continue
        if len(cells) != len(header):
            raise _refuse(name, what, f"line {lineno} has {len(cells)} values",
                          f"{len(header)} values per row, as the header")  # fmt: skip
        row = []
        for col, cell in enumerate(cells, 1):
            x = float(cell) if _DECIMAL.fullmatch(cell.strip(" \t")) else math.nan
            if not math.isfinite(x):
                where = f"line {lineno}, column {col} ({clip(header[col - 1])})"
                problem = f"{where}: {clip(cell)} is not a finite decimal number"
                allowed = "decimal numbers such as 0.25 or -1.5e-3 (no inf, nan or _)"
                raise _refuse(name, what, problem, allowed)
            row.append(x)
        rows.append(row)
    if header is None:
        raise _refuse(name, what, "no header line", "a header line, then rows of numbers")
    return meta, header, rows
