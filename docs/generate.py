"""Pages made when the documentation is built, from the sources that stay true.

* README sections become reStructuredText (``docs/_generated/readme_<slug>.rst``), so the narrative
  pages and the README never disagree: the README is written once, the pages include it.
* ``pfaff <command> --help`` of every command (``docs/_generated/cli_<command>.rst``).
* The model-file keys the loader accepts, probed from the loader itself
  (:func:`loader_keys`; the model-file page must name every one, ``tests/docs``).

Run by ``conf.py`` at ``builder-inited``; also ``python docs/generate.py`` to look at the output.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
OUT = DOCS / "_generated"


# ---------------------------------------------------------------------------- README → rst
def readme_sections(text: str) -> dict[str, str]:
    """``## Title`` sections of the README by title (the text before the first: ``""``)."""
    parts = re.split(r"^## (.+)$", text, flags=re.M)
    out = {"": parts[0]}
    for title, body in zip(parts[1::2], parts[2::2], strict=True):
        out[title.strip()] = body
    return out


def _inline(line: str) -> str:
    """Markdown inline code → rst literals, and the characters rst would read as markup escaped."""
    pieces = re.split(r"(`[^`]+`)", line)
    out = []
    for k, piece in enumerate(pieces):
        if k % 2:
            lit = piece[1:-1]
            before = out[-1][-1:] if out and out[-1] else " "
            pre = "" if before in " (['\"/—–-" else "\\ "
            nxt = pieces[k + 1][:1] if k + 1 < len(pieces) else ""
            post = "" if not nxt or nxt in " .,;:)]'\"/—–-?!" else "\\ "
            out.append(f"{pre}``{lit}``{post}")
        else:
            piece = piece.replace("\\", "\\\\").replace("|", "\\|")
            piece = re.sub(r"(\w)_(?=\W|$)", r"\1\\_", piece)  # a trailing _ is a reference
            piece = re.sub(r"(?<![\w*])\*(?=[\s,.)]|$)", r"\\*", piece)  # a lone *
            out.append(piece)
    return "".join(out)


def to_rst(markdown: str) -> str:
    """The README's markdown (its subset: paragraphs, lists, fences, indented blocks) as rst."""
    lines = markdown.strip("\n").splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        fence = re.match(r"^```(\w*)", line)
        if fence:
            lang = {"bash": "bash", "python": "python"}.get(fence.group(1), "text")
            body = []
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append(lines[i])
                i += 1
            out += (
                ["", f".. code-block:: {lang}", ""] + ["   " + b if b else "" for b in body] + [""]
            )
            i += 1
            continue
        if line.startswith("    ") and (not out or not out[-1].strip()):
            body = []
            while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
                body.append(lines[i])
                i += 1
            while body and not body[-1].strip():
                body.pop()
            out += ["::", ""] + ["   " + b[4:] if b.strip() else "" for b in body] + [""]
            continue
        heading = re.match(r"^(#{3,}) (.+)$", line)
        if heading:
            title = _inline(heading.group(2))
            out += ["", title, "~" * len(title), ""]
        else:
            out.append(_inline(line))
        i += 1
    return "\n".join(out) + "\n"


def escape_docstring(lines: list[str]) -> None:
    """Escape ``|`` (|f| means a norm here, not an rst substitution) in docstring prose, in place:
    not inside literals, doctest lines or literal blocks."""
    literal_indent = None
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        indent = len(line) - len(stripped)
        if literal_indent is not None:
            if stripped and indent <= literal_indent:
                literal_indent = None
            else:
                continue
        if stripped.startswith((">>>", "...")) or "|" not in line:
            if line.rstrip().endswith("::"):
                literal_indent = indent
            continue
        parts = re.split(r"(``[^`]+``|`[^`]+`)", line)
        lines[i] = "".join(p if k % 2 else p.replace("|", "\\|") for k, p in enumerate(parts))
        if line.rstrip().endswith("::"):
            literal_indent = indent


# ---------------------------------------------------------------------------- CLI help
def cli_help(argv: list[str]) -> str:
    """The help of ``pfaff <argv>``, as argparse formats it (80 columns)."""
    import os

    parser = _parser(argv)
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "80"
    try:
        return parser.format_help()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _parser(argv: list[str]):
    import argparse

    from pfaff.cli.main import build_parser

    parser = build_parser()
    for word in argv:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    return parser


def cli_commands() -> list[list[str]]:
    """Every command of ``pfaff``, walking its argparse tree: the top level and each subcommand."""
    import argparse

    out: list[list[str]] = []

    def walk(argv: list[str]) -> None:
        out.append(argv)
        parser = _parser(argv)
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name in action.choices:
                    walk([*argv, name])

    walk([])
    return out


# ---------------------------------------------------------------------------- model-file keys
def loader_keys() -> dict[str, list[str]]:
    """The keys each section of a model file accepts, as the loader itself says.

    For every section of the loader's ``SECTIONS`` a file with an unknown key in it is loaded;
    the loader refuses it listing the keys it allows. A body's ``attitude`` table is probed the
    same way. Nothing here is written by hand.
    """
    from pfaff.modelfile.load import SECTIONS, load_model

    head = '[model]\nname = "probe"\ncoordinates = ["x"]\nparameters = { m = 1.0 }\n'
    tables = {"model", "initial", "simulate"}
    probes = {}
    for sec in sorted(SECTIONS):
        if sec == "model":
            probes[sec] = head.replace("[model]\n", "[model]\nzz_probe = 1\n")
        elif sec in tables:
            probes[sec] = head + f"[{sec}]\nzz_probe = 1\n"
        else:
            probes[sec] = head + f"[[{sec}]]\nzz_probe = 1\n"
    probes["bodies.attitude"] = head + (
        '[[bodies]]\nmass = "m"\ninertia = 1\nposition = ["x", "0"]\n'
        'attitude = { kind = "planar", coordinates = ["x"], zz_probe = 1 }\n'
    )
    keys: dict[str, list[str]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for sec, text in probes.items():
            path = Path(tmp) / "probe.toml"
            path.write_text(text, encoding="utf-8")
            try:
                load_model(path)
            except Exception as e:  # the loader's refusal names what it allows
                allowed = re.search(r"allowed: ([^)]*)\)", str(e))
                if allowed is None:
                    raise RuntimeError(f"the loader did not list the keys of [{sec}]: {e}") from e
                keys[sec] = [k.strip() for k in allowed.group(1).split(",")]
            else:
                raise RuntimeError(f"the loader accepted an unknown key in [{sec}]")
    return keys


# ---------------------------------------------------------------------------- write
PAGES = {
    "intro": "",
    "equations": "Equations and sign convention",
    "use": "Use",
    "overconstrained": "Overconstrained mechanisms",
    "simulate": "Simulate",
    "scale": "How it scales",
    "compiled": "The compiled model",
    "bodies": "Rigid bodies and attitude",
    "linearization": "Linearization",
    "modelfiles": "Model files",
    "viewer": "3-D viewer",
    "cli": "CLI",
    "trust": "Trust",
    "families": "Scale: families",
}


def write(out: Path = OUT) -> None:
    out.mkdir(exist_ok=True)
    sections = readme_sections((ROOT / "README.md").read_text(encoding="utf-8"))
    for name, title in PAGES.items():
        text = to_rst(sections.get(title, "")) if title in sections else ""
        _update(out / f"readme_{name}.rst", text)
    for argv in cli_commands():
        name = "_".join(argv) or "pfaff"
        title = " ".join(["pfaff", *argv])
        body = "\n".join("   " + line if line else "" for line in cli_help(argv).splitlines())
        _update(out / f"cli_{name}.rst", f"{title}\n{'-' * len(title)}\n\n::\n\n{body}\n")
    pages = [out / f"cli_{'_'.join(a) or 'pfaff'}.rst" for a in cli_commands()]
    _update(out / "cli_all.rst", "\n".join(p.read_text(encoding="utf-8") for p in pages))


def _update(path: Path, text: str) -> None:
    """Write only what changed (Sphinx then rebuilds only what changed)."""
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    write()
    for sec, keys in loader_keys().items():
        print(f"[{sec}]", ", ".join(keys))
