"""One declaration per option.

Every option of clsolid is a field of a frozen dataclass (a method's parameters, the back
end's, the command line's own) declared with :func:`option`. The declaration holds
everything the rest needs: the default, what values are allowed (a *check*), a one-line
help, the group it belongs to and whether it is advanced. From it come the API's
validation (:func:`validate`), the command line's flags and ``--help``
(:func:`add_arguments`), the records (:func:`to_record`) and the option reference in the
docs (:func:`reference_rows`).
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import math
import numbers
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator

from ..errors import InputError
from .views import view_set, views_value

#: The key under which a field's :class:`Option` sits in ``dataclasses.field(metadata=...)``.
METADATA_KEY = "clsolid"


# ----------------------------------------------------------------------------- checks


class Check:
    """What values an option takes: ``check(name, value)`` returns the value (normalised) or
    raises :class:`~clsolid.errors.InputError` naming the option, the value and what it may be."""

    #: How the command line reads one word of the option (``type=`` of argparse).
    parse: Callable[[str], Any] | None = str
    #: ``nargs`` of the flag (None: one value).
    nargs: str | int | None = None

    def describe(self) -> str:  # pragma: no cover - overridden
        raise NotImplementedError

    def valid(self, value: Any) -> bool:  # pragma: no cover - overridden
        raise NotImplementedError

    def normalise(self, value: Any) -> Any:
        return value

    def __call__(self, name: str, value: Any) -> Any:
        if not self.valid(value):
            raise InputError(f"{name}={value!r} must be {self.describe()}")
        return self.normalise(value)

    @property
    def choices(self) -> tuple | None:
        return None


def _real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class Int(Check):
    """An integer (not a bool) in ``[lo, hi]`` (no upper bound without *hi*); odd if *odd*."""

    lo: int | None = None
    hi: int | None = None
    odd: bool = False
    parse = int

    def describe(self) -> str:
        kind = "an odd integer" if self.odd else "an integer"
        if self.lo == 1 and self.hi is None and not self.odd:
            return "a positive integer"
        if self.lo is not None and self.hi is not None:
            return f"{kind} in [{self.lo}, {self.hi}]"
        if self.lo is not None:
            return f"{kind} >= {self.lo}"
        return kind if self.hi is None else f"{kind} <= {self.hi}"

    def valid(self, value: Any) -> bool:
        return (isinstance(value, numbers.Integral) and not isinstance(value, bool)
                and (self.lo is None or value >= self.lo) and (self.hi is None or value <= self.hi)
                and (not self.odd or value % 2 == 1))

    def normalise(self, value: Any) -> int:
        return int(value)


@dataclass(frozen=True)
class Real(Check):
    """A finite number (not a bool) between *lo* and *hi*, each bound open if so marked."""

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    parse = float

    def describe(self) -> str:
        low = None if self.lo is None else f"{'>' if self.lo_open else '>='} {self.lo:g}"
        high = None if self.hi is None else f"{'<' if self.hi_open else '<='} {self.hi:g}"
        if low and high:
            return (f"a number in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}"
                    f"{')' if self.hi_open else ']'}")
        return f"a number {low or high}" if (low or high) else "a finite number"

    def valid(self, value: Any) -> bool:
        if not _real(value):
            return False
        if self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo):
            return False
        return self.hi is None or (value < self.hi if self.hi_open else value <= self.hi)


@dataclass(frozen=True)
class Reals(Check):
    """One positive number, or one per scale (a sequence); its length is checked by the class."""

    parse = float
    nargs = "+"

    def describe(self) -> str:
        return "a positive number or a sequence of them (one per scale, finest first)"

    def valid(self, value: Any) -> bool:
        values = (value,) if _real(value) else value
        try:
            return len(values) > 0 and all(_real(v) and v > 0 for v in values)
        except TypeError:
            return False


@dataclass(frozen=True)
class Choice(Check):
    """One of *values* (strings, or integers: the command line reads each word as their type)."""

    values: tuple

    @property
    def parse(self):  # type: ignore[override]
        return type(self.values[0])

    def describe(self) -> str:
        return f"one of {', '.join(map(repr, self.values))}"

    def valid(self, value: Any) -> bool:
        return (isinstance(value, (str, numbers.Integral)) and not isinstance(value, bool)
                and type(value) is not float and value in self.values)

    @property
    def choices(self) -> tuple:
        return self.values


@dataclass(frozen=True)
class Flag(Check):
    """True or False."""

    parse = None

    def describe(self) -> str:
        return "True or False"

    def valid(self, value: Any) -> bool:
        return isinstance(value, bool)


@dataclass(frozen=True)
class Anything(Check):
    """A value the class checks itself (a path, a client object); the command line reads it with *parse*."""

    what: str = "a value"
    reader: Callable[[str], Any] | None = str
    count: str | int | None = None

    @property
    def parse(self):  # type: ignore[override]
        return self.reader

    @property
    def nargs(self):  # type: ignore[override]
        return self.count

    def describe(self) -> str:
        return self.what

    def valid(self, value: Any) -> bool:
        return True


@dataclass(frozen=True)
class PathLike(Anything):
    """A file or folder path (a str or an os.PathLike); the class checks the rest (its suffix, whether it exists)."""

    def valid(self, value: Any) -> bool:
        return isinstance(value, (str, os.PathLike))


# ----------------------------------------------------------------------------- declarations


@dataclass(frozen=True)
class Option:
    """How one option is declared (the metadata of its dataclass field).

    Attributes
    ----------
    help : str
        One line: what the option does.
    group : str
        The command line's group (and the reference's section) it belongs to.
    check : Check
        The values it takes (None is taken too where *none* says what None means).
    advanced : bool
        Shown only by ``--help-all``.
    none : str or None
        What None means (``"by the exemplar"``); None: None is not a value of this option.
    flag : str or None
        The command line's flag; ``""``: ``--`` and the name with dashes; None: none (API only).
    short : str or None
        A one-letter flag beside it (``"-o"``).
    metavar : str or None
        The flag's placeholder in ``--help``.
    positional : bool
        The command line takes it as a positional argument.
    methods : tuple of str or None
        The methods that read it, where the class serves several (None: every one).
    required : bool
        The command line needs it (from a flag or a config file); its default is None.
    """

    help: str
    group: str
    check: Check = field(default_factory=lambda: Anything())
    advanced: bool = False
    none: str | None = None
    flag: str | None = ""
    short: str | None = None
    metavar: str | None = None
    positional: bool = False
    methods: tuple[str, ...] | None = None
    required: bool = False

    def flag_name(self, name: str) -> str | None:
        """The long flag of the field *name* (None: no flag)."""
        if self.flag is None or self.positional:
            return None
        return self.flag or "--" + name.replace("_", "-")


def option(default: Any, help: str, *, group: str, check: Check | None = None, advanced: bool = False,
           none: str | None = None, flag: str | None = "", short: str | None = None, metavar: str | None = None,
           positional: bool = False, methods: tuple[str, ...] | None = None, required: bool = False) -> Any:
    """A dataclass field declared as an option (see :class:`Option` for the arguments)."""
    if default is None and none is None and not required:
        raise TypeError(f"an option whose default is None says what None means (none=...): {help!r}")
    spec = Option(help=help, group=group, check=check or Anything(), advanced=advanced, none=none, flag=flag,
                  short=short, metavar=metavar, positional=positional, methods=methods, required=required)
    return field(default=default, metadata={METADATA_KEY: spec})


def declared(cls_or_instance: Any) -> Iterator[tuple[dataclasses.Field, Option]]:
    """Every field of a dataclass declared with :func:`option`, with its declaration, in order."""
    for f in dataclasses.fields(cls_or_instance):
        spec = f.metadata.get(METADATA_KEY)
        if spec is not None:
            yield f, spec


def names(cls: Any) -> tuple[str, ...]:
    """The names of the options *cls* declares."""
    return tuple(f.name for f, _ in declared(cls))


def validate(instance: Any) -> None:
    """Check every declared field of a frozen dataclass *instance*, normalising it in place
    (call it first in ``__post_init__``; checks across fields follow it)."""
    for f, spec in declared(instance):
        value = getattr(instance, f.name)
        if value is None and (spec.none is not None or spec.required):  # a required one: its caller says so
            continue
        checked = spec.check(f.name, value)
        if checked is not value:
            object.__setattr__(instance, f.name, checked)


def refuse_unknown(given: Iterable[str], valid: Iterable[str], what: str) -> None:
    """Refuse names in *given* that are not in *valid*, naming the closest valid name."""
    valid = tuple(valid)
    unknown = sorted(set(given) - set(valid))
    if not unknown:
        return
    hints = []
    for name in unknown:
        close = difflib.get_close_matches(name, valid, n=1)
        hints.append(f"{name!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    raise InputError(f"unknown option{'s' if len(unknown) > 1 else ''} {', '.join(hints)} for {what}; "
                     f"valid: {', '.join(sorted(valid))}")


def default_text(f: dataclasses.Field, spec: Option) -> str:
    """The default as the help and the reference say it."""
    if spec.required:
        return "required"
    if f.default is None or f.default is dataclasses.MISSING:
        return spec.none or "none"
    if isinstance(f.default, bool):
        return "on" if f.default else "off"
    if isinstance(f.default, (tuple, list)):
        return " ".join(map(str, f.default))
    return str(f.default)


def to_record(instance: Any) -> dict[str, Any]:
    """The declared fields of *instance* as JSON-ready values (tuples as lists)."""
    out = {}
    for f, _ in declared(instance):
        value = getattr(instance, f.name)
        out[f.name] = list(value) if isinstance(value, tuple) else value
    return out


# ----------------------------------------------------------------------------- command line


@dataclass
class _Flag:
    """One flag of a generated parser, possibly serving fields of several classes."""

    name: str
    spec: Option
    default: Any  # the first declaring class's
    helps: list[tuple[str, str, str]]  # (who, help, default in words)


def _default_words(f: dataclasses.Field, spec: Option) -> str:
    """The default as ``--help`` says it ('' where nothing is worth saying: off, or none)."""
    if spec.required:
        return "required"
    if f.default is False or (f.default is None and spec.none == "none"):
        return ""
    return f"default {default_text(f, spec)}"


def _help_text(helps: list[tuple[str, str, str]]) -> str:
    """One help line for a flag that several classes declare: one text with each default, or each in turn."""
    texts = {text for _, text, _ in helps}
    if len(helps) == 1 or (len(texts) == 1 and len({d for _, _, d in helps}) == 1):
        _, text, default = helps[0]
        return f"{text}; {default}" if default else text
    if len(texts) == 1:
        defaults = ", ".join(f"{d.removeprefix('default ')} ({who})" for who, _, d in helps if d)
        return f"{helps[0][1]}; default {defaults}"
    return "; ".join(f"{who}: {text}" + (f", {default}" if default else "") for who, text, default in helps)


def add_arguments(parser: argparse.ArgumentParser, sources: Iterable[tuple[str, Any]], *,
                  groups: dict[str, str], advanced_groups: Iterable[str] = (), show_all: bool = True) -> dict:
    """Add a flag to *parser* for every option of the dataclasses in *sources*.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The parser (a subcommand's).
    sources : iterable of (str, dataclass type)
        Who declares the options (``"ml"``, :class:`~clsolid.ml.params.MLParams`) and the class.
        A name declared by several classes gets one flag, its help naming each.
    groups : dict
        Title of each group, in the order ``--help`` shows them.
    advanced_groups : iterable of str
        Groups shown only with *show_all* (``--help-all``).
    show_all : bool
        Show the advanced groups and options.

    Returns
    -------
    dict
        Flag destination -> the names in *sources* of the classes that declare it.

    Every flag's default is ``argparse.SUPPRESS``: an option the user did not give is absent
    from the namespace, so that each class's own default (or a config file's value) applies.
    """
    sources = tuple(sources)
    flags: dict[str, _Flag] = {}
    owners: dict[str, list[str]] = {}
    for who, cls in sources:
        for f, spec in declared(cls):
            if spec.flag is None:
                continue
            if spec.group not in groups:
                raise KeyError(f"{cls.__name__}.{f.name}: group {spec.group!r} is not one of {tuple(groups)}")
            words = (who, spec.help.rstrip("."), _default_words(f, spec))
            entry = flags.get(f.name)
            if entry is None:
                flags[f.name] = _Flag(f.name, spec, f.default, [words])
            else:
                if (entry.spec.check.parse, entry.spec.check.nargs) != (spec.check.parse, spec.check.nargs):
                    raise TypeError(f"option {f.name!r} is read differently by {owners[f.name]} and {who}")
                entry.helps.append(words)
            owners.setdefault(f.name, []).append(who)
    hidden = set(advanced_groups)
    made = {key: parser.add_argument_group(title) for key, title in groups.items()}
    for entry in flags.values():
        spec = entry.spec
        shown = show_all or not (spec.advanced or spec.group in hidden)
        kwargs: dict[str, Any] = {"help": _help_text(entry.helps).replace("%", "%%") if shown else argparse.SUPPRESS}
        check = spec.check
        if isinstance(check, Flag):
            # off by default: the flag alone; on, or decided later: --name and --no-name
            kwargs["action"] = "store_true" if entry.default is False else argparse.BooleanOptionalAction
        else:
            if check.parse is not None:
                kwargs["type"] = check.parse
            if check.nargs is not None:
                kwargs["nargs"] = check.nargs
            choices = _union_choices(entry.name, sources)
            if choices:
                kwargs["choices"] = choices
            if spec.metavar:
                kwargs["metavar"] = spec.metavar
        group = made[spec.group]
        if spec.positional:
            group.add_argument(entry.name, nargs="?", default=argparse.SUPPRESS, **kwargs)
        else:
            flags_of = [spec.short] if spec.short else []
            group.add_argument(*flags_of, spec.flag_name(entry.name), dest=entry.name, default=argparse.SUPPRESS,
                               **kwargs)
    return {name: tuple(who) for name, who in owners.items()}


def _union_choices(name: str, sources: Iterable[tuple[str, Any]]) -> tuple | None:
    out: list = []
    for _, cls in sources:
        for f, spec in declared(cls):
            if f.name == name and spec.check.choices:
                out += [c for c in spec.check.choices if c not in out]
    return tuple(out) or None


# ----------------------------------------------------------------------------- reference


def reference_rows(cls: Any) -> list[dict[str, str]]:
    """One row per option of *cls*: name, flag, values, default, help, group, advanced."""
    rows = []
    for f, spec in declared(cls):
        check = spec.check
        rows.append({"name": f.name, "flag": spec.flag_name(f.name) or ("(positional)" if spec.positional else ""),
                     "values": check.describe() + (", or None" if spec.none else ""),
                     "default": default_text(f, spec), "help": spec.help, "group": spec.group,
                     "advanced": "yes" if spec.advanced else ""})
    return rows


def reference_markdown(cls: Any, title: str) -> str:
    """The option reference of *cls* as a Markdown section: one table row per option."""
    lines = [f"## {title}", "", (cls.__doc__ or "").strip().split("\n\n")[0].replace("\n    ", " "), "",
             "| option | flag | values | default | what it does |", "|---|---|---|---|---|"]
    for row in reference_rows(cls):
        cells = [f"`{row['name']}`", f"`{row['flag']}`" if row["flag"].startswith("-") else row["flag"],
                 row["values"], row["default"], row["help"] + (" (advanced)" if row["advanced"] else "")]
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines) + "\n"


def documented(cls: type) -> type:
    """Class decorator (after ``@dataclass``): append to *cls*'s docstring a numpydoc
    ``Attributes`` section built from its declarations, so that each option's help, values and
    default are written once and read everywhere (``help()``, the API reference)."""
    lines = ["", "Attributes", "----------"]
    for f, spec in declared(cls):
        kind = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
        lines.append(f"{f.name} : {kind}")
        lines.append(f"    {spec.help[0].upper()}{spec.help[1:].rstrip('.')}. Values: {spec.check.describe()}"
                     + (f", or None ({spec.none})" if spec.none else "") + f". Default: {default_text(f, spec)}.")
    doc = (cls.__doc__ or "").rstrip()
    indent = "    " if "\n    " in doc else ""
    cls.__doc__ = doc + "\n" + "\n".join(indent + line if line else line for line in lines) + "\n"
    return cls


# ----------------------------------------------------------------------------- shared by every method


def _levels_word(text: str) -> int | None:
    if text.lower() in ("all", "none"):
        return None
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--levels must be an integer or 'all', not {text!r}") from None


@dataclass(frozen=True)
class Views(Check):
    """The constrained views: 2, 3, or two or three view names (:func:`clsolid.core.views.view_set`)."""

    parse = staticmethod(lambda text: int(text) if text.strip().isdigit() else text)

    def describe(self) -> str:
        return ("2 (front + right), 3 (front + right + top) or two view names such as 'front+top' "
                "(views: front, right, top)")

    def valid(self, value: Any) -> bool:
        return view_set(value) is not None

    def normalise(self, value: Any) -> int | str:
        return views_value(view_set(value))


@dataclass(frozen=True)
class Levels(Int):
    """A number of grey levels; the command line also takes ``all`` (None: 8-bit)."""

    parse = staticmethod(_levels_word)


def views_option() -> Any:
    """``views``: the constrained views, declared once for every method."""
    return option(3, "constrained views: 3 = front, right and top (every section alike), 2 = front and right "
                  "only, sharing y (layered or directional materials), or a pair by name (front+top)",
                  group="essentials", metavar="N|PAIR",
                  check=Views())


def despeckle_option() -> Any:
    """``despeckle``: the last step on segmented exemplars, declared once for every method."""
    return option(True, "segmented exemplars: a voxel that no face neighbour shares its phase with takes the "
                  "phase most of them have, at the end", group="method", check=Flag())


def neighborhood_option(default: int) -> Any:
    """``neighborhood``: the window's side, declared once for every method (each its own default)."""
    return option(default, "odd side of the square window in each view", group="method", check=Int(3, 31, odd=True),
                  metavar="K")


def scales_option() -> Any:
    """``scales``: the multi-scale pyramid's depth, declared once for every method."""
    return option(3, "scales (each halves the exemplar and the block)", group="method", check=Int(1, 8), metavar="N")


def levels_option() -> Any:
    """``levels``: the grey levels an exemplar is reduced to, declared once for every method."""
    return option(32, "most grey levels; an exemplar with at most this many values keeps them (phases)",
                  group="method", check=Levels(2, 65536), none="all 256 levels of an 8-bit image", metavar="N|all")
