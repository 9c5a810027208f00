"""The licence file matches the package metadata, and the citation file and the documentation's
references page cite tvist's two papers."""

from __future__ import annotations

import re
from pathlib import Path

from ruamel.yaml import YAML

ROOT = Path(__file__).resolve().parents[2]

#: The two papers, as their texts title them.
FD_TVIST_TITLE = (
    "Vibration control of industrial robot arms by multi-mode time-varying input shaping"
)
ZTDIS_TITLE = "Modified zero time delay input shaping for industrial robot with flexibility"


def test_license_is_the_apache_2_text_the_package_declares():
    pyproject = (ROOT / "pyproject.toml").read_text()
    declared = re.search(r'^license = \{ text = "([^"]+)" \}$', pyproject, re.MULTILINE)
    assert declared and declared.group(1) == "Apache-2.0"
    text = (ROOT / "LICENSE").read_text()
    assert text.lstrip().startswith("Apache License\n")
    assert "Version 2.0, January 2004" in text
    # The full text, not a notice: all nine sections and the appendix.
    for section in range(1, 10):
        assert f"\n   {section}. " in text, section
    assert "END OF TERMS AND CONDITIONS" in text
    assert "APPENDIX: How to apply the Apache License to your work." in text


def test_citation_file_cites_tvist_and_both_papers():
    cff = YAML(typ="safe").load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0"
    assert cff["type"] == "software"
    assert cff["title"].startswith("tvist")
    assert cff["license"] == "Apache-2.0"
    assert cff["authors"] and cff["message"]
    by_title = {ref["title"]: ref for ref in cff["references"]}
    assert set(by_title) == {FD_TVIST_TITLE, ZTDIS_TITLE}
    fd_tvist = by_title[FD_TVIST_TITLE]
    assert [a["family-names"] for a in fd_tvist["authors"]] == [
        "Thomsen",
        "Søe-Knudsen",
        "Balling",
        "Zhang",
    ]
    assert fd_tvist["journal"] == "Mechanism and Machine Theory"
    assert fd_tvist["year"] == 2020
    assert [a["family-names"] for a in by_title[ZTDIS_TITLE]["authors"]] == ["Zhao", "Tomizuka"]


def test_the_references_page_names_both_papers_and_the_readme_points_to_it():
    page = (ROOT / "docs" / "theory" / "references.md").read_text()
    flat = " ".join(page.replace("*", "").split())
    assert FD_TVIST_TITLE in flat
    assert ZTDIS_TITLE in flat
    assert "CITATION.cff" in flat and "LICENSE" in flat
    # The README names where to cite from and links the page.
    readme = (ROOT / "README.md").read_text()
    assert "CITATION.cff" in readme and "LICENSE" in readme
    assert "(docs/theory/references.md)" in readme
