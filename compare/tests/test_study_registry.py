"""A new study is one module plus one registration (issue 42 item 2): a preset registered
with its own ``run`` is run by ``treeimpact sweep --preset NAME``, started by ``report
--with-study NAME`` into its own folder, listed by --preset's choices, and a kind registered for its
data file is rendered by its own body in the report; docs/architecture.md "Adding a study"
names exactly these files."""

import json
from pathlib import Path

import pytest

from treeimpact.compare.interface.cli import main
from treeimpact.compare.report import study_kinds
from treeimpact.compare.report.studies import StudySection
from treeimpact.compare.report.validity import presets

ROOT = Path(__file__).resolve().parents[2]


def _run_fake(out, scenario, *, workers=None, scheduler=None, progress=None, grid=None,
              retry_failed=False):
    """The fake study: writes fake.json with the tree it was given, and its page."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fake.json").write_text(json.dumps({"fake": {"tree": str(scenario)}}))
    (out / "summary.md").write_text("fake study")
    return {"json": out / "fake.json"}


@pytest.fixture
def fake(monkeypatch):
    """The fake study registered as a new module registers itself, undone afterwards."""
    monkeypatch.delitem(presets.PRESETS, "fake", raising=False)
    monkeypatch.delitem(study_kinds.KINDS, "fake", raising=False)
    presets.register(presets.Preset("fake", "open-center", (), run=_run_fake,
                                    folder="fake", help="fake (a test's) about 1 s"))
    study_kinds.register_kind(study_kinds.StudyKind(
        "fake", "fake.json", "fake", "fake_body", "f", lambda data: set()))
    yield
    presets.PRESETS.pop("fake")  # monkeypatch then puts back what was there: nothing
    study_kinds.KINDS.pop("fake")


def test_a_registered_study_runs_from_the_command_line(fake, tmp_path, capsys):
    assert main(["sweep", "--preset", "fake", "--out", str(tmp_path / "f"),
                 "--scenario", "central-leader"]) == 0
    assert json.loads((tmp_path / "f" / "fake.json").read_text()) == {
        "fake": {"tree": "central-leader"}}
    assert main(["sweep", "--preset", "nope", "--out", str(tmp_path / "n")]) == 2
    assert "fake" in capsys.readouterr().err.splitlines()[-1]  # the choices read the registry
    from treeimpact.compare.interface.api_studies import _study_folders
    from treeimpact.compare.report.validity.study_job import StudyJob

    assert _study_folders(["default", "fake"]) == {"default": "study", "fake": "fake"}
    job = StudyJob("fake", tmp_path / "fake", ["treeimpact"], scenarios=["open-center"])
    assert job.argv[:3] == ["treeimpact", "sweep", "--preset"] and job.argv[3] == "fake"
    assert "--sensitivity-scenario" not in job.argv and job.name == "fake"


def test_its_kind_is_found_in_its_folder_and_needs_its_body(fake, tmp_path):
    _run_fake(tmp_path / "fake", "open-center")
    section = StudySection(tmp_path / "fake", page_dir=tmp_path)
    assert list(section.kinds) == ["fake"] and section.study is None
    assert section.context()["bodies"] == ["fake_body"]
    assert section.context()["f"] == {"fake": {"tree": "open-center"}}
    with pytest.raises(Exception, match="fake_body"):  # its template is its one more file
        section.render("html")


def test_a_name_is_registered_once():
    with pytest.raises(ValueError, match="'default' is registered already"):
        presets.register(presets.Preset("default", "central-leader", ()))
    with pytest.raises(ValueError, match="'design' is registered already"):
        study_kinds.register_kind(study_kinds.KINDS["design"])


def test_the_docs_name_the_files_a_new_study_touches():
    text = (ROOT / "docs" / "architecture.md").read_text()
    part = text[text.index("## Adding a study"):]
    part = part[:part.index("\n## ", 4)] if "\n## " in part[4:] else part
    for name in ("compare/report/validity/presets.py", "compare/report/validity/__init__.py",
                 "compare/report/study_kinds.py", "register(Preset(", "register_kind("):
        assert name in part, name
