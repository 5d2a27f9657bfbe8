"""Read the Markdown parts of the environments' docstrings (Gymnasium's style) as reStructuredText.

The environment classes (``simgrip.envs.pick.PickEnv``, ``simgrip.envs.pick_multi.PickMultiEnv``) write
their tables the way Gymnasium's own environments do: ``## Heading`` lines and Markdown pipe tables,
readable with ``help()``. Everything else in those docstrings is already reStructuredText (``literal``,
:class: roles, :math:). This ``autodoc-process-docstring`` hook rewrites just those two constructs:

* ``## Heading`` (any level) becomes ``.. rubric:: Heading``;
* a pipe table (a header row, a ``|---|`` rule, body rows) becomes a ``list-table`` with a header row;
  cells are kept verbatim, so their inline markup is read as it is written.

Other docstrings are left alone. A pipe table whose rows do not all have the header's number of cells
is a build error naming the object, not a silently mangled table.
"""

from __future__ import annotations

import re

_HEADING = re.compile(r"^(\s*)#{1,6}\s+(\S.*?)\s*#*\s*$")
_RULE = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def _cells(line: str) -> list[str]:
    body = line.strip()
    if body.startswith("|"):
        body = body[1:]
    if body.endswith("|") and not body.endswith("\\|"):
        body = body[:-1]
    cells = re.split(r"(?<!\\)\|", body)
    return [c.strip().replace("\\|", "|") for c in cells]


def _is_row(line: str) -> bool:
    return line.lstrip().startswith("|")


def convert(lines: list[str], where: str) -> list[str]:
    """``lines`` of one docstring with Markdown headings and pipe tables rewritten (see the module)."""
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        heading = _HEADING.match(line)
        if heading:
            indent, text = heading.groups()
            out += [f"{indent}.. rubric:: {text}", ""]
            i += 1
            continue
        if _is_row(line) and i + 1 < len(lines) and _RULE.match(lines[i + 1]):
            indent = line[: len(line) - len(line.lstrip())]
            header = _cells(line)
            rows = []
            i += 2
            while i < len(lines) and _is_row(lines[i]):
                row = _cells(lines[i])
                if len(row) != len(header):
                    raise ValueError(f"{where}: a Markdown table row has {len(row)} cells, its header "
                                     f"{len(header)}: {lines[i].strip()!r}")
                rows.append(row)
                i += 1
            if out and out[-1].strip():
                out.append("")
            out += [f"{indent}.. list-table::", f"{indent}   :header-rows: 1", ""]
            for row in [header] + rows:
                for k, cell in enumerate(row):
                    out.append(f"{indent}   {'* -' if k == 0 else '  -'} {cell or ' '}".rstrip())
            out.append("")
            continue
        out.append(line)
        i += 1
    return out


def _process(app, what, name, obj, options, lines):
    if not name.startswith("simgrip.envs"):
        return
    lines[:] = convert(list(lines), name)


def setup(app):
    app.connect("autodoc-process-docstring", _process)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
