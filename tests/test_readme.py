"""The README is a short front page: its two set-up commands are what CI runs (keep them from drifting
apart), and it links every page of the manual in docs/, whose links lead somewhere."""

from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def readme_commands() -> list[str]:
    text = (REPO / "README.md").read_text()
    block = text.split("```sh\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def test_readme_opens_with_two_commands_and_ci_runs_the_test_one():
    demo, tests = readme_commands()
    assert "expressive-mocap demo" in demo
    assert "pytest" in tests
    ci = [
        line
        for line in (REPO / ".ci" / "run").read_text().splitlines()
        if line and not line.startswith(("#", "set ", "cd "))
    ]
    assert ci == [tests]


def test_readme_is_a_front_page_linking_every_page_of_the_manual():
    text = (REPO / "README.md").read_text()
    assert len(text.encode()) < 8192, "the README is the front page: the manual goes in docs/"
    pages = sorted(p.name for p in (REPO / "docs").glob("*.md"))
    assert pages and all(f"](docs/{page})" in text for page in pages), pages


def anchors(markdown: str) -> set[str]:
    """The anchors GitHub gives a page's headings (lower case, punctuation dropped, spaces as -)."""
    import re

    text = re.sub(r"```.*?```", "", markdown, flags=re.S)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in re.findall(r"^#+ (.*)$", text, re.M)}


def test_the_pages_relative_links_lead_to_files_and_headings_that_exist():
    import re

    for page in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        for target, anchor in re.findall(r"\]\(([^)#:\s]*)(?:#([^)]*))?\)", page.read_text()):
            path = page.parent / target if target else page
            assert path.exists(), f"{page.name}: {target}"
            if anchor and path.suffix == ".md":
                assert anchor in anchors(path.read_text()), f"{page.name}: {target}#{anchor}"
