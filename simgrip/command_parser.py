"""The command lines' argument parser: a one-line error with exit code 2, and negative numbers read as values.

Every command of the project parses with :class:`CommandParser` (the ``simgrip`` command, the examples, the
``python -m`` modules): argparse's own refusals (a wrong type, a missing argument) then read as the values the
commands check themselves, ``PROG: error: MESSAGE (see PROG --help)`` on one line of stderr, status 2, the usage
left to ``--help``; and ``--kappa -1e6``, ``--gamma -inf`` reach the option's type (argparse's own pattern misses
exponents, ``inf`` and ``nan``: "expected one argument").
"""

from __future__ import annotations

import argparse
import re

__all__ = ["CommandParser", "EXIT_USAGE"]

#: Exit status of a usage error (argparse's, and every value a command refuses).
EXIT_USAGE = 2
#: An option value that is a negative number: ``-5``, ``-5.5``, ``-.5``, ``-1e6``, ``-1E-3``, ``-inf``, ``-nan``.
NEGATIVE_NUMBER = re.compile(r"^-(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan)$", re.IGNORECASE)


class CommandParser(argparse.ArgumentParser):
    """argparse with a consistent one-line error and exit code 2, and negative numbers read as values."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")
