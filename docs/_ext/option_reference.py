"""Write the option reference as a Markdown page, from the options' declarations.

At ``builder-inited`` this extension calls ``option_reference_source`` (``"module:function"``),
which returns the page's Markdown (for clsolid, :func:`clsolid.cli.synth.option_reference`:
one table per declaring class, every option with its flag, values, default and help), and
writes it to ``option_reference_output`` under the source folder.
"""

from __future__ import annotations

import importlib
from pathlib import Path


def write_reference(app) -> None:
    module, _, name = app.config.option_reference_source.partition(":")
    text = getattr(importlib.import_module(module), name)()
    target = Path(app.srcdir) / app.config.option_reference_output
    if not target.is_file() or target.read_text(encoding="utf-8") != text:  # unchanged: no rebuild
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")


def setup(app):
    app.add_config_value("option_reference_source", "", "env")
    app.add_config_value("option_reference_output", "reference/options.md", "env")
    app.connect("builder-inited", write_reference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
