"""Write the command-line reference as a Markdown page, from the argparse parser itself.

At ``builder-inited`` this extension imports the parser factory named by the
``cli_reference_parser`` setting (``"module:function"``), builds the parser (with
``show_all=True`` where the factory takes that keyword, so that groups hidden from
``--help`` are listed too) and writes ``cli_reference_output`` (a path under the source
folder): one section per subcommand, one subsection per argument group, and every option
with its flags, metavar, default and help. It knows nothing of clsolid's options: it walks
the parser's action groups, so a parser reorganised into other groups comes out as it is.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
from pathlib import Path

#: Characters that Markdown (MyST, with dollar maths) would read as markup in help text.
_MARKUP = set("\\*_[]<>|$")


def escape(text: str) -> str:
    """Escape Markdown markup in plain text; text between paired backticks stays code."""
    pieces = text.split("`")
    if len(pieces) % 2 == 0:  # a lone backtick: no code spans, the backtick escaped too
        return "".join("\\" + c if c in _MARKUP or c == "`" else c for c in text)
    return "`".join(piece if i % 2 else "".join("\\" + c if c in _MARKUP else c for c in piece)
                    for i, piece in enumerate(pieces))


def load_parser(spec: str) -> argparse.ArgumentParser:
    """Build the parser named ``"module:function"``, asking for every group if it can."""
    module, _, name = spec.partition(":")
    factory = getattr(importlib.import_module(module), name)
    try:
        takes_all = "show_all" in inspect.signature(factory).parameters
    except (TypeError, ValueError):  # a builtin or a callable without a signature
        takes_all = False
    return factory(show_all=True) if takes_all else factory()


def subcommands(parser: argparse.ArgumentParser) -> list[tuple[str, argparse.ArgumentParser, str]]:
    """(name, parser, one-line help) of each subcommand, in the order they were added."""
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
            seen = set()
            for name, sub in action.choices.items():
                if id(sub) in seen:  # an alias of a subcommand already listed
                    continue
                seen.add(id(sub))
                found.append((name, sub, helps.get(name) or ""))
    return found


def flags(action: argparse.Action) -> str:
    """The option's flags with its metavar (``-o OUTPUT``, ``--shape Z Y X``), or its name."""
    if not action.option_strings:
        metavar = action.metavar or action.dest
        return f"`{metavar if isinstance(metavar, str) else ' '.join(metavar)}`"
    if action.nargs == 0:
        return ", ".join(f"`{s}`" for s in action.option_strings)
    formatter = argparse.HelpFormatter("clsolid")
    args = formatter._format_args(action, action.dest.upper())
    return ", ".join(f"`{s} {args}`" for s in action.option_strings)


def _value(value) -> str:
    if isinstance(value, (list, tuple)):
        return " ".join(str(v) for v in value)
    if isinstance(value, Path):
        return str(value)
    return str(value)


def default(action: argparse.Action) -> str | None:
    """The default worth stating: not for flags that are off, nor when there is none."""
    value = action.default
    if value is None or value is argparse.SUPPRESS:
        return None
    if isinstance(action, argparse.BooleanOptionalAction):
        return "on" if value else "off"
    if action.nargs == 0 and value is False:  # a flag that is off unless given
        return None
    return _value(value)


def help_text(action: argparse.Action, prog: str) -> str:
    """The help with argparse's ``%(default)s``-style fields filled in, as ``--help`` shows it."""
    text = action.help or ""
    if "%" in text:
        params = dict(vars(action), prog=prog)
        for name, value in list(params.items()):
            if value is argparse.SUPPRESS:
                del params[name]
            elif isinstance(value, (list, tuple)):
                params[name] = ", ".join(str(v) for v in value)
        if params.get("choices") is not None:
            params["choices"] = ", ".join(str(c) for c in action.choices)
        try:
            text = text % params
        except (KeyError, TypeError, ValueError):
            pass
    return text


def option_lines(action: argparse.Action, prog: str) -> list[str]:
    """One list item: flags, then the help, then what the help does not say itself."""
    text = help_text(action, prog).strip()
    parts = [escape(text)] if text else []
    if action.choices is not None and action.metavar is not None:  # the flags do not show them
        parts.append("Choices: " + ", ".join(f"`{c}`" for c in action.choices))
    value = default(action)
    if value is not None and "default" not in text.lower():
        parts.append(f"Default: `{value}`")
    body = ". ".join(p.rstrip(".") for p in parts)
    return [f"- {flags(action)}" + (f": {body}." if body else "")]


def group_sections(parser: argparse.ArgumentParser, prog: str) -> list[str]:
    lines: list[str] = []
    for group in parser._action_groups:
        actions = [a for a in group._group_actions
                   if a.help is not argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)]
        if not actions:
            continue
        title = group.title or "options"
        lines += ["", f"### {escape(title[:1].upper() + title[1:])}", ""]
        if group.description:
            lines += [escape(group.description), ""]
        for action in actions:
            lines += option_lines(action, prog)
    return lines


def render(parser: argparse.ArgumentParser, title: str = "Command-line reference") -> str:
    prog = parser.prog
    lines = [f"# {title}", "",
             "<!-- Generated at build time by docs/_ext/cli_reference.py from the parser itself; "
             "do not edit. -->", ""]
    if parser.description:
        lines += [escape(parser.description), ""]
    lines += [f"Every option of `{prog}`, subcommand by subcommand and group by group, read from the "
              "parser itself when this site was built.", ""]
    if parser.epilog:  # e.g. the exit statuses, kept verbatim
        lines += ["```text", parser.epilog.rstrip(), "```", ""]
    subs = subcommands(parser)
    if not subs:
        lines += group_sections(parser, prog)
    for name, sub, summary in subs:
        lines += ["", f"## `{prog} {name}`", ""]
        text = sub.description or summary
        if text:
            lines += [escape(text), ""]
        lines += group_sections(sub, f"{prog} {name}")
    return "\n".join(lines).rstrip() + "\n"


def write_reference(app) -> None:
    parser = load_parser(app.config.cli_reference_parser)
    target = Path(app.srcdir) / app.config.cli_reference_output
    text = render(parser)
    if not target.is_file() or target.read_text(encoding="utf-8") != text:  # unchanged: no rebuild
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")


def setup(app):
    app.add_config_value("cli_reference_parser", "", "env")
    app.add_config_value("cli_reference_output", "reference/cli.md", "env")
    app.connect("builder-inited", write_reference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
