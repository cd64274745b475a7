"""The docs and comments describe the code, not its history: src/'s comments and docstrings name no
GPU model (figures measured on one belong in benchmarks/RESULTS.md), no issue and no work session;
docs/DESIGN.md stays a short design (<= 2,500 words), with the task pages beside it."""
import ast
import io
import re
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "rayvr"
DOCS = ROOT / "docs"
# GPU models (NVIDIA's datacenter and desktop parts, AMD's), issue and session numbers. An OpenXR
# session (XrSession) is code, not history: only "session" followed by a number counts.
FORBIDDEN = re.compile(r"\b(G?[AHB]100|G?[HB]200|[AH]800|RTX ?\d{4}|GTX ?\d{3,4}|MI\d{3}X?)\b"
                       r"|\bissues? #?\d+|\bsessions? \d+", re.IGNORECASE)


def python_comments(path: Path) -> list[tuple[int, str]]:
    """(line, text) of the comments and docstrings of a Python file."""
    text = path.read_text()
    out = [(t.start[0], t.string) for t in tokenize.generate_tokens(io.StringIO(text).readline)
           if t.type == tokenize.COMMENT]
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                out.append((node.body[0].lineno, doc))
    return out


def glsl_comments(path: Path) -> list[tuple[int, str]]:
    """(line, text) of the // and /* */ comments of a shader."""
    text = path.read_text()
    found = re.finditer(r"//[^\n]*|/\*.*?\*/", text, re.DOTALL)
    return [(text.count("\n", 0, m.start()) + 1, m.group(0)) for m in found]


def test_source_comments_name_no_gpu_issue_or_session():
    found = []
    for path in sorted(SRC.rglob("*")):
        if path.suffix == ".py":
            comments = python_comments(path)
        elif path.suffix in (".glsl", ".comp", ".vert", ".frag"):
            comments = glsl_comments(path)
        else:
            continue
        for line, text in comments:
            for m in FORBIDDEN.finditer(text):
                found.append(f"{path.relative_to(ROOT)}:{line}: {m.group(0)!r}")
    assert not found, ("say what the code does and why, not on which GPU or when (measurements go to "
                       "benchmarks/RESULTS.md):\n" + "\n".join(found))


def test_the_check_finds_what_it_looks_for(tmp_path):
    py = tmp_path / "x.py"
    py.write_text('"""Fast on the H200."""\nx = "H100"   # the renderer string, not a comment\n# issue 14\n')
    glsl = tmp_path / "x.glsl"
    glsl.write_text("// measured in session 11\nint h100 = 0;\n/* an H100\n figure */\n")
    hits = [m.group(0) for _, t in python_comments(py) + glsl_comments(glsl) for m in FORBIDDEN.finditer(t)]
    assert hits == ["issue 14", "H200", "session 11", "H100"]
    assert not FORBIDDEN.search("the OpenXR session ends; a pass issues the barriers")


def test_design_is_short_and_the_task_pages_exist():
    words = len((DOCS / "DESIGN.md").read_text().split())
    assert words <= 2500, f"docs/DESIGN.md has {words} words (at most 2,500: measurements go to benchmarks/RESULTS.md)"
    for page in ("adding-a-pass.md", "adding-a-lobe.md", "adding-a-sink.md"):
        assert (DOCS / page).is_file(), page


def test_doc_links_resolve():
    """Every relative link of the docs' Markdown names a file that exists."""
    missing = []
    for page in [*DOCS.glob("*.md"), ROOT / "README.md", ROOT / "benchmarks" / "RESULTS.md"]:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if "://" not in target and not (page.parent / target).exists():
                missing.append(f"{page.relative_to(ROOT)}: {target}")
    assert not missing, missing
