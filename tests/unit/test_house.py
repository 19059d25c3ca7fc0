"""The house: jobs and their keys, settings built once, the report's format and versions, the store."""

import json

import pytest

from brdfremap.core.cli import main
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.job.execute import AdapterPool, execute
from brdfremap.core.job.job import Job, Target, resolve
from brdfremap.core.job.report import READS_FROM, SCHEMA_VERSION, Report, parse_report, read_report
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Material
from brdfremap.core.data.settings import DEFAULTS, Settings
from brdfremap.core.run.store import Store, owned
from brdfremap_example.adapter import ToyAdapter
from helpers import registry_of

SRC = Material(adapter="toy", model="toy", params={"diffuse": [0.6, 0.3, 0.1], "specular": 0.8, "alpha": 0.15})
SCENE = ProbeScene(resolution=32)


def _registry():
    return registry_of("toy", ToyAdapter)


def _job(**changes):
    base = dict(source=SRC, target=Target(adapter="toy", model="toy"), scene=SCENE, settings=Settings(scheme="one"),
                fit_same_model=True)  # a fit to report on
    return Job(**{**base, **changes})


def test_a_job_key_is_what_determines_the_result_and_nothing_else():
    reg = _registry()
    key = resolve(_job(), reg).job.key()
    # Labels and names are not inputs; defaults written out or left out are the same job.
    assert resolve(_job(label="elsewhere.yaml"), reg).job.key() == key
    named = SRC.model_copy(update={"name": "a name", "params": {**SRC.params, "unused": 0.5}})
    assert resolve(_job(source=named), reg).job.key() == key
    assert resolve(_job(scene=SCENE.model_copy(update={"name": "x", "note": "y"})), reg).job.key() == key
    # What changes the fit changes the key.
    for changed in (_job(settings=Settings(scheme="two")), _job(scene=SCENE.with_(spp=32)),
                    _job(target=Target(adapter="toy", model="toy", fix={"specular": 0.5})),
                    _job(source=SRC.model_copy(update={"params": {**SRC.params, "alpha": 0.2}}))):
        assert resolve(changed, reg).job.key() != key
    # A job goes through JSON (a worker, a report) and comes back the same job.
    job = resolve(_job(), reg).job
    assert Job.model_validate_json(job.model_dump_json()).key() == key


def test_a_job_is_checked_before_any_render_naming_the_field():
    reg = _registry()
    with pytest.raises(ConfigError, match="m.yaml: params.alpha: 7 is outside"):
        from brdfremap.core.job.job import Where

        resolve(_job(source=SRC.model_copy(update={"params": {"alpha": 7}})), reg, Where(source_file="m.yaml"))
    # A data file names an adapter; it never points at a renderer definition to run.
    with pytest.raises(ConfigError, match="'r.yaml' is a file: a data file names an installed adapter"):
        from brdfremap.core.job.job import Where

        resolve(_job(source=SRC.model_copy(update={"adapter": "r.yaml"})), reg, Where(source_file="m.yaml"))


def test_settings_defaults_exist_once_and_the_cli_reads_them(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    help_text = capsys.readouterr().out
    from brdfremap.core.cli.options import flag

    for name, info in Settings.model_fields.items():
        assert flag(name) in help_text
        assert f"(default {getattr(DEFAULTS, name)})" in " ".join(help_text.split())
    with pytest.raises(Exception, match="extra"):
        Settings(schme="one")


def _report(tmp_path):
    reg = _registry()
    out = execute(resolve(_job(), reg), AdapterPool(reg))
    return out


def test_the_report_reads_back_and_other_versions_are_clear_errors(tmp_path):
    out = _report(tmp_path)
    doc = out.report.document()
    assert doc["schema_version"] == SCHEMA_VERSION and doc["key"] == out.report.job.key()
    assert doc["reliable"] == (doc["verdict"] == "ok") and isinstance(doc["findings"], list)
    assert parse_report(doc, "r.json").document() == doc  # what is written reads back as written
    older = {k: v for k, v in doc.items() if k != "schema_version"}
    with pytest.raises(ConfigError, match="r.json: written by an older brdf-remap"):
        parse_report(older, "r.json")
    with pytest.raises(ConfigError, match=r"r.json: written by a newer brdf-remap \(report schema 99"):
        parse_report({**doc, "schema_version": 99}, "r.json")
    with pytest.raises(ConfigError, match="r.json: metrics: Field required"):
        parse_report({k: v for k, v in doc.items() if k != "metrics"}, "r.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ConfigError, match="bad.json: cannot read it as JSON"):
        read_report(bad)
    # A result of format 6 or before (no held inputs a source needs, a metal judged beyond white
    # Lambertians) is run again.
    reads = str(SCHEMA_VERSION) if READS_FROM == SCHEMA_VERSION else f"{READS_FROM} to {SCHEMA_VERSION}"
    with pytest.raises(ConfigError, match=rf"older brdf-remap \(report schema 6; this one reads {reads}\): "
                                          "run the job again"):
        parse_report({**doc, "schema_version": 6}, "r.json")


def test_the_store_keeps_a_result_whole_and_finds_it_by_key(tmp_path):
    out = _report(tmp_path)
    store = Store(tmp_path / "s")
    store.save("a", out)
    assert store.find("a", out.report.key).document() == out.report.document()
    assert store.find("a", "another key") is None
    import hashlib

    (tmp_path / "s/a/stale.txt").write_text("from an older result")
    (tmp_path / "s/a/notes.txt").write_text("the user's, listed by a forged record")
    doc = json.loads((tmp_path / "s/a/result.json").read_text())
    sha = hashlib.sha256(b"from an older result").hexdigest()
    (tmp_path / "s/a/result.json").write_text(json.dumps({**doc, "files": doc["files"] + [
        {"name": "stale.txt", "sha256": sha, "bytes": 20}, {"name": "notes.txt", "sha256": "0" * 64, "bytes": 37}]}))
    store.save("a", out)  # a file the previous result wrote (its hash) and this one has not is removed
    assert not (tmp_path / "s/a/stale.txt").exists()
    assert (tmp_path / "s/a/notes.txt").exists()  # not what it wrote: never removed
    (tmp_path / "s/a/target.exr").write_bytes(b"x")
    stored = store.inspect("a")
    assert stored.report is None and "target.exr is missing or does not match" in stored.problem
    assert not list((tmp_path / "s/a").glob(".staging-*"))


def test_a_folder_is_owned_by_one_run_at_a_time(tmp_path, capsys):
    with owned(tmp_path / "o"):
        with pytest.raises(ConfigError, match="another brdf-remap run is writing this folder"):
            with owned(tmp_path / "o"):
                pass
    with owned(tmp_path / "o"):  # released when the first run ends
        with pytest.raises(ConfigError, match="is inside .*/o, which another brdf-remap run is writing"):
            with owned(tmp_path / "o" / "points" / "00-001"):  # a sweep's point is the sweep's to write
                pass
    with pytest.raises(ConfigError, match="--out: is empty"):
        with owned(""):
            pass
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match="cannot write here"):
        with owned(tmp_path / "file" / "below"):
            pass


@pytest.mark.parametrize("name", ["report", "material", "scene", "experiment", "job", "settings", "renderer", "convert",
                                  "lookup", "experiment-summary"])
def test_remap_schema_prints_a_valid_json_schema(name, capsys):
    import jsonschema

    assert main(["schema", name]) == 0
    schema = json.loads(capsys.readouterr().out)
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["type"] == "object" and schema["properties"]


def test_remap_schema_of_an_unknown_format_is_one_line(capsys):
    assert main(["schema", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown file format 'nope' (known: convert, experiment, experiment-summary, job, lookup, material" in err[0]


def test_a_report_document_validates_against_the_published_schema(tmp_path):
    from reports import validator

    doc = _report(tmp_path).report.document()
    assert not list(validator().iter_errors(doc))
    assert list(validator().iter_errors({**doc, "verdict": "fine"}))  # the schema does constrain
    assert Report.model_validate(doc).reliable == doc["reliable"]


def test_an_error_keeps_its_parts_and_they_cross_processes():
    import pickle

    from brdfremap.core.data.errors import RenderError

    err = pickle.loads(pickle.dumps(ConfigError("must be positive", file="m.yaml", field="params.alpha")))
    assert str(err) == "m.yaml: params.alpha: must be positive"
    assert (err.message, err.where, err.file, err.field) == ("must be positive", "m.yaml: params.alpha", "m.yaml",
                                                            "params.alpha")
    err = pickle.loads(pickle.dumps(RenderError("worker unavailable", where="cycles")))
    assert str(err) == "cycles: worker unavailable" and err.message == "worker unavailable"


def test_a_study_fits_the_given_inputs_and_a_job_from_a_file_names_its_keys():
    from brdfremap.core.job.job import Where

    assert Settings().inputs == "needed" and Settings().for_study().inputs == "given"
    assert Settings(fit_scene="as-given").for_study().fit_scene == "as-given"
    assert Where().fix_field("alpha") == "--fix alpha" and Where().field("--scene", "scene") == "--scene"
    filed = Where(fix_prefix="target.fix", command_line=False)
    assert filed.fix_field("alpha") == "target.fix.alpha" and filed.field("--scene", "scene") == "scene"


def test_lightings_and_schemes_are_typed_and_written_as_their_strings(tmp_path):
    """A report's conditions and schemes are enum members in Python, their strings in result.json:
    the document reads back with the same members and writes the same text (issue 46)."""
    from brdfremap.core.data.scene import Lighting
    from brdfremap.core.data.settings import Scheme

    report = _report(tmp_path).report
    assert isinstance(report.scheme, Scheme) and isinstance(report.scheme_used, Scheme)
    conditions = [c.condition for c in report.validation] + \
        [f.condition for f in report.findings if isinstance(getattr(f, "condition", None), str)]
    assert conditions and all(isinstance(c, Lighting) for c in conditions)
    text = json.dumps(report.document(), sort_keys=True)
    assert f'"scheme": "{report.scheme.value}"' in text and f'"condition": "{conditions[0].value}"' in text
    again = parse_report(json.loads(text), "r.json")
    assert json.dumps(again.document(), sort_keys=True) == text
    assert again.scheme is report.scheme
    assert [c.condition for c in again.validation] == [c.condition for c in report.validation]
