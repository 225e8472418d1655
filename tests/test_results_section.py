"""The README's results section is rewritten by `physics-bench` only while it is
the text it last wrote (benchmarks/summary.update_section): a section edited by
hand is never overwritten (a study run into the default folder used to replace
537 lines of the README, hand-written analysis included, with the bare tables)."""
from benchmarks import summary


def _readme(tmp_path, text):
    path = tmp_path / "README.md"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_readme_without_markers_gets_the_section_appended(tmp_path):
    path = _readme(tmp_path, "# Title\n\nIntro.\n")
    assert summary.update_section(path, "## Results\n\ntable v1")
    text = path.read_text(encoding="utf-8")
    assert text.startswith("# Title\n\nIntro.\n\n<!-- results:begin sha1=")
    assert text.endswith("## Results\n\ntable v1\n<!-- results:end -->\n")


def test_a_section_it_wrote_is_replaced_and_the_text_around_it_kept(tmp_path):
    path = _readme(tmp_path, "# Title\n")
    summary.update_section(path, "## Results\n\ntable v1")
    path.write_text(path.read_text(encoding="utf-8") + "\n## After\n", encoding="utf-8")
    assert summary.update_section(path, "## Results\n\ntable v2")
    text = path.read_text(encoding="utf-8")
    assert "table v2" in text and "table v1" not in text
    assert text.startswith("# Title\n") and text.endswith("\n## After\n")
    assert text.count("results:begin") == 1


def test_a_section_edited_by_hand_is_left_as_it_is(tmp_path):
    path = _readme(tmp_path, "# Title\n")
    summary.update_section(path, "## Results\n\ntable v1")
    edited = path.read_text(encoding="utf-8").replace("table v1", "table v1, and why")
    path.write_text(edited, encoding="utf-8")
    assert not summary.update_section(path, "## Results\n\ntable v2")
    assert path.read_text(encoding="utf-8") == edited


def test_a_section_without_a_digest_counts_as_edited_by_hand(tmp_path):
    text = "# T\n\n<!-- results:begin -->\n## Limits\n\nhand text\n<!-- results:end -->\n"
    path = _readme(tmp_path, text)
    assert not summary.update_section(path, "## Results\n\ntables")
    assert path.read_text(encoding="utf-8") == text


def test_write_reports_a_readme_it_left_alone(tmp_path):
    text = "# T\n\n<!-- results:begin -->\nhand text\n<!-- results:end -->\n"
    path = _readme(tmp_path, text)
    out = tmp_path / "results"
    out.mkdir()
    written = summary.write(str(out), update_readme=True, readme=str(path))
    assert written[0].endswith("README_results.md")
    assert written[1].startswith("not ") and "hand edits" in written[1]
    assert path.read_text(encoding="utf-8") == text
