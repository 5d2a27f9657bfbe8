"""The documentation's examples run, their shown output is what they print, and its links lead somewhere.

Two checks over the Markdown pages in ``docs/`` (the Sphinx site's sources) and the README:

* every ```` ```python ```` block of ``docs/**/*.md`` is executed, each in a fresh namespace (in this process,
  so imports are shared and the whole file stays in seconds), in a scratch working directory; a block followed
  directly by a ```` ```text ```` block must print exactly that text (the docs' shown output is checked, not
  just that the code runs). A Python example that must not run here (a training run of minutes) is written as
  a ``{code-block} python`` directive whose ``:caption:`` starts with ``not run:`` and gives the reason, which
  the page then shows; any other ``{code-block} python`` is an error, so no example is silently left out;
* every relative link and image of ``docs/**/*.md`` and ``README.md`` names a file that exists, and a
  ``#fragment`` names a heading of the target page (GitHub's and MyST's anchor of a heading).

The Sphinx build itself (``python -m sphinx -W``) runs in CI (``.ci/run``), not here: Sphinx is an optional
dependency (``pip install ".[docs]"``).
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)

_FENCE = re.compile(r"^(`{3,}|~{3,})\s*(.*?)\s*$")


def fenced_blocks(text: str):
    """(fence line, info string, options, body, closing line index) of every top-level fenced block of a page.

    ``options`` are a MyST directive's leading ``:name: value`` lines (removed from ``body``).
    """
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, info, start = m.group(1), m.group(2), i + 1
        j = i + 1
        while j < len(lines) and not (lines[j].startswith(fence[0] * len(fence)) and not lines[j].strip(fence[0]).strip()):
            j += 1
        body = lines[i + 1:j]
        options = {}
        if info.startswith("{"):
            while body and body[0].startswith(":"):
                key, _, value = body.pop(0)[1:].partition(":")
                options[key.strip()] = value.strip()
        yield start, info, options, "\n".join(body) + "\n", j
        i = j + 1


def _examples():
    """pytest params: each Python block of the docs, with the output it must print (None: not shown)."""
    out = []
    for page in PAGES:
        blocks = list(fenced_blocks(page.read_text(encoding="utf-8")))
        lines = page.read_text(encoding="utf-8").splitlines()
        for k, (start, info, options, body, end) in enumerate(blocks):
            words = info.split()
            if words[:1] == ["python"]:
                expected = None
                if k + 1 < len(blocks):
                    nstart, ninfo, _, nbody, _ = blocks[k + 1]
                    between = lines[end + 1:nstart - 1]
                    if ninfo.split()[:1] == ["text"] and not any(x.strip() for x in between):
                        expected = nbody
                rel = page.relative_to(ROOT)
                out.append(pytest.param(str(rel), start, body, expected, id=f"{rel}:{start}"))
    return out


def unrun_problems(text: str) -> list[str]:
    """Python blocks of a page that are neither run (```python) nor marked ``:caption: not run: <reason>``."""
    problems = []
    for start, info, options, _, _ in fenced_blocks(text):
        words = info.split()
        if words[:1] in (["{code-block}"], ["{code}"], ["{sourcecode}"]) and words[1:2] in (["python"], ["py"]):
            caption = options.get("caption", "").strip().strip("\"'")  # MyST reads a quoted value as YAML
            if not re.match(r"not run: \S", caption):
                problems.append(f"line {start}: a {{code-block}} python must carry ':caption: not run: <reason>' "
                                f"(or be a ```python block, which the tests run)")
    return problems


EXAMPLES = _examples()


def test_docs_have_examples():
    """The pages the examples live on are found (a parser that finds nothing would pass every check)."""
    pages = {p.values[0] for p in EXAMPLES}
    assert {"docs/getting-started.md", "docs/python.md", "docs/environments.md", "docs/sweeps.md"} <= pages, pages


@pytest.mark.parametrize("page, line, source, expected", EXAMPLES)
def test_example_runs(page, line, source, expected, tmp_path, monkeypatch):
    """Each example runs in a fresh namespace; a shown output is exactly what it prints."""
    monkeypatch.chdir(tmp_path)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(source, f"{page}:{line}", "exec"), {"__name__": "__docs_example__"})
    if expected is not None:
        got = [x.rstrip() for x in printed.getvalue().rstrip("\n").splitlines()]
        want = [x.rstrip() for x in expected.rstrip("\n").splitlines()]
        assert got == want, f"{page}:{line} printed\n" + "\n".join(got) + "\nthe page shows\n" + "\n".join(want)


def test_unrun_examples_say_why():
    """A Python block that is not executed is marked so on the page, with its reason."""
    problems = [f"{p.relative_to(ROOT)} {x}" for p in PAGES for x in unrun_problems(p.read_text(encoding="utf-8"))]
    assert not problems, "\n".join(problems)
    bad = "```{code-block} python\n:caption: an example\n\nprint(1)\n```\n"
    good = '```{code-block} python\n:caption: "not run: needs a cluster"\n\nprint(1)\n```\n'
    assert len(unrun_problems(bad)) == 1 and unrun_problems(good) == []


_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_INLINE_CODE = re.compile(r"(`+)(?:(?!\1).)+?\1", re.DOTALL)


def _prose(text: str) -> str:
    """``text`` without its fenced blocks and inline code (links there are examples, not links)."""
    lines = text.splitlines()
    keep = [True] * len(lines)
    for start, _, _, _, end in fenced_blocks(text):
        for i in range(start - 1, min(end + 1, len(lines))):
            keep[i] = False
    return _INLINE_CODE.sub("", "\n".join(x if k else "" for x, k in zip(lines, keep)))


def _slug(heading: str) -> str:
    """The anchor GitHub (and MyST's ``myst_heading_anchors``) gives a heading."""
    text = _INLINE_CODE.sub(lambda m: m.group(0).strip("`"), heading.strip()).lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.+?)\s*#*\s*$", _prose(page.read_text(encoding="utf-8")), re.M)}


def _links():
    for page in PAGES + [ROOT / "README.md"]:
        for m in _LINK.finditer(_prose(page.read_text(encoding="utf-8"))):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, mailto:
                continue
            yield page, target


def test_links_resolve():
    """Every relative link of the docs and the README names an existing file (and heading)."""
    checked, broken = 0, []
    for page, target in _links():
        path, _, fragment = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        checked += 1
        if not dest.exists():
            broken.append(f"{page.relative_to(ROOT)}: {target} (no such file)")
        elif fragment and dest.suffix == ".md" and fragment not in _anchors(dest):
            broken.append(f"{page.relative_to(ROOT)}: {target} (no heading with that anchor)")
    assert checked > 50, f"only {checked} links found: the link pattern is broken"
    assert not broken, "broken links:\n" + "\n".join(broken)


def test_link_check_catches_a_broken_link(tmp_path):
    """The link pattern sees links, images and titles, and skips code (the check above could not fail else)."""
    page = tmp_path / "p.md"
    page.write_text("see [a](missing.md), ![b](img.png \"t\") and `[c](code.md)`\n\n```text\n[d](e.md)\n```\n")
    found = [m.group(1) for m in _LINK.finditer(_prose(page.read_text()))]
    assert found == ["missing.md", "img.png"]
    assert _slug("Where the parameter space ends") == "where-the-parameter-space-ends"
    assert _slug("`simgrip sweep` on Dask") == "simgrip-sweep-on-dask"


_CODE_SPAN = re.compile(r"`([^`\n]+)`")


def _code_spans():
    for page in PAGES + [ROOT / "README.md"]:
        for m in _CODE_SPAN.finditer(page.read_text(encoding="utf-8")):
            yield page.relative_to(ROOT), m.group(1)


def _resolves(dotted: str) -> bool:
    import importlib

    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_names_in_the_docs_exist():
    """Every ``simgrip.x.y`` the pages name imports, every repository path they name exists, and every
    environment id they name is registered (or retired, ``simgrip.envs.RETIRED``: still built through
    ``retired_spec``): a module moved or renamed cannot leave the docs behind."""
    import gymnasium

    import simgrip  # noqa: F401  registers the environments
    from simgrip.envs import RETIRED

    stale = []
    for page, span in _code_spans():
        for name in re.findall(r"\bsimgrip(?:\.[A-Za-z_]\w*)+", span):
            if not _resolves(name):
                stale.append(f"{page}: {name} (no such module or attribute)")
        for env_id in re.findall(r"\bsimgrip/[A-Z][A-Za-z]*-v\d+\b", span):
            if env_id not in gymnasium.registry and env_id not in RETIRED:
                stale.append(f"{page}: {env_id} (no such environment)")
        for path in re.findall(r"\b(?:simgrip|envs|tests|examples|models)/[a-z_][\w/.-]*\.(?:py|xml)\b", span):
            if not (ROOT / path).exists():
                stale.append(f"{page}: {path} (no such file)")
    assert not stale, "the docs name what does not exist:\n" + "\n".join(sorted(set(stale)))
