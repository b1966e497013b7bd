"""The files a user writes, declared: every table and key of a kind of TOML file (a scene, a sweep
file, a design study) with its type, range, unit, default and one line of documentation. One
checker reads any of them (`read`), and reports a mistake as one line,
`file:line: 'full.key' = value: reason`; one writer turns a schema into its reference page
(`reference`, docs/reference/).

A schema is a list of `Table`s. A table's name is dotted; a part in angle brackets names a family
of tables (`trajectory.<dof>`: one table per DOF, `drive.leg.<i>`), and a table with `many` is an
array of tables (`[[axis]]`). A key's type is one of cosim.engine.values; `Free` leaves a table of
names and values to the application (an FMU's parameters are checked against the FMU), and
`Items` is a list of inline tables with keys of their own. What involves more than one key (a
finer start needs its step, a value that must be one of the parameter set's) the application
checks after `read`, reporting through the same `Document.fail`.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from .errors import InputError
from .values import REQUIRED, Items


# -- keys and tables ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Key:
    name: str
    type: Any
    doc: str
    default: Any = None  # None: may be left out (the application's own default applies); REQUIRED

    @property
    def unit(self) -> str:
        return getattr(self.type, "unit", "")


@dataclass(frozen=True)
class Table:
    name: str  # dotted; "<x>" a family of tables; "" the file's top level
    doc: str
    keys: tuple[Key, ...] = ()
    many: bool = False            # an array of tables, [[name]]
    names: tuple[str, ...] = ()   # what a family's <x> may be (empty: any, the application checks)
    required: bool = False

    def key(self, name: str) -> Key | None:
        return next((k for k in self.keys if k.name == name), None)


@dataclass(frozen=True)
class Schema:
    kind: str         # "scene file"
    doc: str
    tables: tuple[Table, ...]
    error: type[InputError] = InputError
    groups: bool = False  # the tables are groups of names (settings given by name), not TOML tables

    def table(self, name: str) -> Table:
        return next(t for t in self.tables if t.name == name)

    def extended(self, name: str, keys: Sequence[Key]) -> "Schema":
        """The schema with more keys in one table (a sweep's targets)."""
        tables = tuple(Table(t.name, t.doc, (*t.keys, *keys), t.many, t.names, t.required) if t.name == name else t
                       for t in self.tables)
        return Schema(self.kind, self.doc, tables, self.error, self.groups)


# -- where a key stands in the file's text -----------------------------------------------------------

def line_of(text: str, table: str, key: str, index: int | None = None) -> int:
    """The line (1-based) on which `key` stands inside [table] (or inside the index-th [[table]], 0
    the first; the table's header itself when key is ""), also inside an inline table there; the
    header [table.key] of a table of that name; 0 if the file does not give it there."""
    assignment = re.compile(r'(^|[{,\s])"?' + re.escape(key) + r'"?\s*=')
    inside, count = table == "", -1
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if line.startswith("["):
            current = line.strip("[]").strip()
            if index is None:
                inside = current == table
                if current == (f"{table}.{key}" if table else key):
                    return number
            else:
                count += current == table and line.startswith("[[")
                inside = current == table and line.startswith("[[") and count == index
            if inside and not key:
                return number
            continue
        if inside and key and assignment.search(line):
            return number
    return 0


def split_key(full: str) -> list[str]:
    """A dotted key's parts, quoted names kept whole: 'drive.parameters."motor.resistance"' ->
    ['drive', 'parameters', 'motor.resistance']. Raises ValueError for text that is not a key."""
    try:
        data = tomllib.loads(f"{full} = 0")
    except tomllib.TOMLDecodeError:
        raise ValueError(f"{full!r} is not a TOML key (quote a name with dots: 'drive.parameters.\"motor.resistance\"')") \
            from None
    parts = []
    while isinstance(data, dict):
        (name, data), = data.items()
        parts.append(name)
    return parts


# -- a file read against its schema ------------------------------------------------------------------

@dataclass
class Document:
    """A TOML file's document, checked against its schema: `value` gives a key's value (or its
    default), `table`, `family` and `entries` its tables, and `fail` the one-line error for any
    key of it."""
    schema: Schema
    path: Path
    text: str
    data: dict = field(default_factory=dict)
    given: Mapping[str, str] = field(default_factory=dict)  # an override's dotted key -> how it was given ('--set ...')

    def table(self, name: str) -> dict:
        """[name]'s keys and tables ({} where the file has none)."""
        found = self.data
        for part in name.split(".") if name else []:
            found = found.get(part, {}) if isinstance(found, dict) else {}
        return found if isinstance(found, dict) else {}

    def value(self, table: str, key: str, default: Any = None) -> Any:
        """The key's value in [table] (a dotted table name: "trajectory.x"), else its schema's
        default, else `default`."""
        found = self.table(table)
        if key in found:
            return found[key]
        declared = _declared(self.schema, table)
        own = declared.key(key) if declared else None
        return own.default if own is not None and own.default not in (None, REQUIRED) else default

    def family(self, name: str) -> dict[str, dict]:
        """The tables of a family by their names: "trajectory.<dof>" -> {"x": {...}, ...}."""
        parent = name.rsplit(".", 1)[0]
        return {k: v for k, v in self.table(parent).items()
                if isinstance(v, dict) and (found := _declared(self.schema, f"{parent}.{k}")) and found.name == name}

    def entries(self, name: str) -> list[dict]:
        """The tables of an array of tables, [[name]]."""
        found = self.data.get(name, [])
        return found if isinstance(found, list) else []

    def line(self, full: str) -> int:
        """The line of a full key ('trajectory.x.sines[1].amplitude', 'axis[2].values'; a table's
        name: its header), the nearest enclosing one's where the file does not give it, or 0."""
        parts = _parts(full)
        for cut in range(len(parts), 0, -1):
            names, index = [], None
            for part in parts[:cut - 1]:
                name, k = _indexed(part)
                names.append(name)
                table = _declared(self.schema, ".".join(names))
                if k is not None and table is not None and table.many:
                    index = k - 1
            key, k = _indexed(parts[cut - 1])
            table = _declared(self.schema, ".".join([*names, key]))
            if k is not None and table is not None and table.many:
                found = line_of(self.text, ".".join([*names, key]), "", k - 1)
            else:
                found = line_of(self.text, ".".join(names), key, index)
            if found:
                return found
        return 0

    def given_for(self, full: str) -> str | None:
        """How the value at the full key (or a table or list above it) was set over the file, if it
        was ('--set step=-1e-3'), else None."""
        return next((how for key, how in self.given.items() if _parts(full)[:len(_parts(key))] == _parts(key)), None)

    def where(self, full: str) -> str:
        """Where a key's value comes from, as an error names it: 'file:line', or how it was set over
        the file ('--set step=-1e-3 (over file)')."""
        given, line = self.given_for(full), self.line(full)
        if given is None and not self._in_file(full):  # a table the file has not: made by what was set in it
            given = next((how for key, how in self.given.items() if _parts(key)[:len(_parts(full))] == _parts(full)), None)
        return f"{given} (over {self.path})" if given else f"{self.path}:{line}" if line else f"{self.path}"

    def _in_file(self, full: str) -> bool:
        """Whether the file's own text gives the key or table (an indexed one is taken as given)."""
        try:
            found: Any = tomllib.loads(self.text)
        except tomllib.TOMLDecodeError:
            return True
        for part in _parts(full):
            if not isinstance(found, dict) or part not in found:
                return "[" in part
            found = found[part]
        return True

    def fail(self, full: str, problem: str, value: Any = None) -> InputError:
        """The schema's error for the key `full`: `file:line: 'full' = value: problem`, or
        `file:line: 'full' problem` where no value is given ("is missing")."""
        where = self.where(full)  # a value set over the file named as it was given, not at the file's line
        shown = f"'{full}' = {_shown(value)}:" if value is not None else f"'{full}'"
        return self.schema.error(f"{where}: {shown}{'' if problem.startswith(':') else ' '}{problem}")


def _shown(value: Any) -> str:
    """A value as a TOML file writes it (true, not True); text and the rest as Python shows it."""
    return ("true" if value else "false") if isinstance(value, bool) else repr(value)


def _parts(full: str) -> list[str]:
    """'drive.parameters."motor.resistance"' -> ['drive', 'parameters', 'motor.resistance'];
    indices stay on their part ('sines[1]')."""
    return [p.replace('"', "") for p in re.findall(r'"[^"]*"(?:\[\d+\])?|[^.]+', full)]


def _indexed(part: str) -> tuple[str, int | None]:
    found = re.fullmatch(r"(.*)\[(\d+)\]", part)
    return (found.group(1), int(found.group(2))) if found else (part, None)


def _matches(table: Table, given: Sequence[str]) -> bool:
    """Whether the first len(given) parts of the table's name name `given` (a family's <x> any of
    its names)."""
    declared = table.name.split(".") if table.name else []
    return len(declared) >= len(given) and all(
        d == g or (d.startswith("<") and (not table.names or g in table.names)) for d, g in zip(declared, given))


def _declared(schema: Schema, name: str) -> Table | None:
    """The schema's table of this name, a family's member matched to its family."""
    given = name.split(".") if name else []
    return next((t for t in schema.tables if len(t.name.split(".") if t.name else []) == len(given)
                 and _matches(t, given)), None)


def _children(schema: Schema, name: str) -> dict[str, Table | None]:
    """The tables directly below [name]: their name (a family's "<x>") -> the table, or None for
    a table that only holds others (like [drive.leg])."""
    given = name.split(".") if name else []
    out: dict[str, Table | None] = {}
    for table in schema.tables:
        parts = table.name.split(".") if table.name else []
        if len(parts) > len(given) and _matches(table, given):
            child = parts[len(given)]
            out[child] = table if len(parts) == len(given) + 1 else out.get(child)
    return out


def read(schema: Schema, path: str | Path, overrides: Mapping[str, Any] | None = None,
         text: str | None = None, data: dict | None = None, given: Mapping[str, str] | None = None) -> Document:
    """Reads and checks a file against its schema: its text and document (or the given ones, read
    before), with values set at dotted keys over it (`overrides`, as if the file said them; `given`:
    how some were given, '--set KEY=VALUE', which their errors name instead of the file's line);
    every mistake raises the schema's error, one line."""
    path = Path(path)
    if data is None:
        text, data = _load(schema, path)
    document = Document(schema, path, text or "", _with_overrides(schema, path, data, overrides or {}), dict(given or {}))
    _check_table(document, "", document.data, "")
    return document


def _load(schema: Schema, path: Path) -> tuple[str, dict]:
    if not path.is_file():
        raise schema.error(f"{path}: no such {schema.kind}" + (" (a folder)" if path.is_dir() else ""))
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as problem:
        raise schema.error(f"{path}: cannot be read: {problem}") from None
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as problem:
        raise schema.error(f"{path}: not valid TOML: {problem}") from None


def _with_overrides(schema: Schema, path: Path, data: dict, overrides: Mapping[str, Any]) -> dict:
    """A copy of the document with values set at dotted keys (tables made as needed)."""
    import copy
    data = copy.deepcopy(data)
    for key, value in overrides.items():
        try:
            *tables, name = split_key(key)
        except ValueError as error:
            raise schema.error(f"{path}: {error}") from None
        table = data
        for t in tables:
            table = table.setdefault(t, {})
            if not isinstance(table, dict):
                raise schema.error(f"{path}: {key!r}: {t!r} is a value in the file, not a table")
        table[name] = value
    return data


def _check_table(document: Document, name: str, values: Any, shown: str) -> None:
    """Checks [name] (`shown`: its full name, with an array's index) and every table below it."""
    declared = _declared(document.schema, name)
    children = _children(document.schema, name)
    if not isinstance(values, dict):
        raise document.fail(shown, f"must be a table ([{shown}])", values)
    for key, value in values.items():
        full = f"{shown}.{key}" if shown else key
        own = declared.key(key) if declared else None
        if own is not None:
            _check_value(document, own, value, full)
            continue
        below = f"{name}.{key}" if name else key
        table = _declared(document.schema, below)
        if table is not None and table.many:
            if not isinstance(value, list):
                raise document.fail(full, f"must be [[{below}]] tables", value)
            for k, entry in enumerate(value, start=1):
                _check_table(document, below, entry, f"{full}[{k}]")
        elif table is not None or key in children:
            _check_table(document, below, value, full)
        else:
            known = sorted({*(k.name for k in (declared.keys if declared else ())),
                            *(c for c in children if not c.startswith("<")),
                            *(n for c, t in children.items() if c.startswith("<") and t for n in t.names)})
            raise document.fail(full, "is not a known key" + (f" (known here: {', '.join(known)})" if known else ""))
    for key in declared.keys if declared else ():
        if key.default is REQUIRED and key.name not in values:
            raise document.fail(f"{shown}.{key.name}" if shown else key.name, "is missing")
    for child, table in children.items():
        if table is not None and table.required and child not in values:
            raise document.fail(f"{shown}.{child}" if shown else child, "is missing")


def _check_value(document: Document, key: Key, value: Any, full: str) -> None:
    problem = key.type.problem(value)
    if problem is not None:
        raise document.fail(full, problem, value)
    if not isinstance(key.type, Items):
        return
    if key.type.most is not None and len(value) > key.type.most:
        raise document.fail(full, f"has {len(value)} entries; at most {key.type.most}")
    for k, entry in enumerate(value, start=1):
        item = f"{full}[{k}]"
        if not isinstance(entry, dict):
            raise document.fail(item, f"must be an inline table {{{', '.join(i.name for i in key.type.keys)}}}", entry)
        for name, given in entry.items():
            own = next((i for i in key.type.keys if i.name == name), None)
            if own is None:
                raise document.fail(f"{item}.{name}", "is not a known key (known here: "
                                    f"{', '.join(i.name for i in key.type.keys)})")
            _check_value(document, own, given, f"{item}.{name}")
        for own in key.type.keys:
            if own.default is REQUIRED and own.name not in entry:
                raise document.fail(f"{item}.{own.name}", "is missing")


# -- the reference page ------------------------------------------------------------------------------

def reference(schema: Schema, title: str) -> str:
    """The schema as a Markdown page: a section per table, a row per key (type and range, unit,
    default, what it is)."""
    lines = [f"# {title}", "", "<!-- generated from the schema by scripts/reference.py; do not edit -->", "",
             schema.doc, ""]
    for table in schema.tables:
        header = table.name if schema.groups else f"`[[{table.name}]]`" if table.many else f"`[{table.name}]`" \
            if table.name else "The file"
        lines += [f"## {header}", "", table.doc + (" Required." if table.required else ""), ""]
        if table.keys:
            lines += _key_rows(table.keys)
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def _key_rows(keys: Sequence[Key], prefix: str = "") -> list[str]:
    rows = ["| key | type | unit | default | meaning |", "|---|---|---|---|---|"]
    nested = []
    for key in keys:
        default = "required" if key.default is REQUIRED else "" if key.default is None else f"`{_toml(key.default)}`"
        cells = [f"`{prefix}{key.name}`", key.type.describe(), key.unit, default, key.doc]
        rows.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
        if isinstance(key.type, Items):
            nested.append(key)
    for key in nested:
        rows += ["", f"Each entry of `{prefix}{key.name}`:", "", *_key_rows(key.type.keys)[0:]]
    return rows


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return f"{value:g}" if isinstance(value, float) else str(value)
