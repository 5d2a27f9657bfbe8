"""A Sphinx directive that renders the ``simgrip`` command line from its own argparse parsers.

``simgrip-cli`` imports :func:`simgrip.cli.build_parser` at build time and writes, for the top-level
parser and for each sub-command in the order the parser registers them: the one-line help, the
description, the usage line as argparse prints it, and every argument group as a definition list
(option strings with their metavar, then the help text with argparse's ``%(default)s`` expanded).
Nothing here is hand-copied, so the page cannot fall behind the parser; a sub-command without help
text, or an option without help, is a build error rather than a silent gap.
"""

from __future__ import annotations

import argparse
import contextlib
import os

from docutils import nodes
from sphinx.util.docutils import SphinxDirective


def _subcommands(parser: argparse.ArgumentParser):
    """(name, help, sub-parser) for every sub-command of ``parser``, in registration order."""
    for action in parser._actions:  # argparse keeps no public list of sub-parsers
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
            return [(name, helps.get(name), sub) for name, sub in action.choices.items()]
    return []


@contextlib.contextmanager
def _columns(width: int):
    """argparse wraps usage and help at the terminal's width (``COLUMNS``): fix it, so every build is the same."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)
    try:
        yield
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


class CliReference(SphinxDirective):
    """``simgrip-cli``: no arguments; renders every sub-command of :func:`simgrip.cli.build_parser`."""

    has_content = False

    def run(self):
        with _columns(100):
            return self._run()

    def _run(self):
        from simgrip.cli import build_parser

        parser = build_parser()
        out = [self._paragraph(parser.description)]
        out.append(nodes.literal_block(text=parser.format_usage().strip()))
        for name, text, sub in _subcommands(parser):
            if not text:
                raise self.error(f"simgrip {name}: the sub-command has no help text")
            out.append(self._command(name, text, sub))
        return out

    def _paragraph(self, text: str) -> nodes.paragraph:
        return nodes.paragraph(text=" ".join(text.split()))

    def _command(self, name: str, text: str, sub: argparse.ArgumentParser) -> nodes.section:
        title = f"simgrip {name}"
        section = nodes.section(ids=[nodes.make_id(f"cli-{name}")], names=[nodes.fully_normalize_name(title)])
        section += nodes.title("", "", nodes.literal(title, title))
        self.state.document.note_implicit_target(section, section)
        section += self._paragraph(text[0].upper() + text[1:] + ".")
        if sub.description:
            section += self._paragraph(sub.description)
        section += nodes.literal_block(text=sub.format_usage().strip())
        formatter = sub._get_formatter()
        for group in sub._action_groups:
            actions = [a for a in group._group_actions if not isinstance(a, argparse._HelpAction)]
            if not actions:
                continue
            section += nodes.rubric(text=group.title)
            items = nodes.definition_list()
            for action in actions:
                if not action.help:
                    raise self.error(f"simgrip {name}: {action.dest} has no help text")
                invocation = formatter._format_action_invocation(action)
                term = nodes.term("", "", nodes.literal(invocation, invocation))
                body = nodes.definition("", self._paragraph(formatter._expand_help(action)))
                items += nodes.definition_list_item("", term, body)
            section += items
        return section


def setup(app):
    app.add_directive("simgrip-cli", CliReference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
