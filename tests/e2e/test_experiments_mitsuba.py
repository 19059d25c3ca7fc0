"""`remap sweep` and `remap roundtrip` end to end with real Mitsuba renders (small versions of
the shipped Fig. 5 and Fig. 6 experiments)."""

import csv
import json
import os
import signal
import subprocess
import sys
import time

import yaml

from brdfremap.core.cli import main
from reports import read_result

CONDUCTORS = {
    "kind": "sweep", "name": "small Fig. 5",
    "source": {"adapter": "mitsuba", "model": "ashikhmin_shirley", "params": {"alpha": 0.2}},
    "sweep": {"param": "material", "values": ["Au", "Cu", "Cr", "Ag"]},
    "target": {"adapter": "mitsuba", "model": "ward", "fix": {"diffuse_reflectance": 0.0}},
    "scene": {"resolution": 64},
    "options": {"validation": "none"},  # judged on the probe, as the paper's Fig. 5 (configs/experiments)
    "plot": {"x": "source.reflectivity", "y": "target.specular_reflectance", "channels": "each"},
}


def _write(tmp_path, doc, name="exp.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc))
    return path


def _rows(out):
    return {r["point"]: r for r in csv.DictReader((out / "results.csv").open())}


def _table(out):
    """results.csv without the seconds columns (wall time differs between runs)."""
    return [{k: v for k, v in r.items() if "seconds" not in k} for r in csv.DictReader((out / "results.csv").open())]


def test_sweep_writes_csv_plots_and_flags_the_trimmed_point(tmp_path, mitsuba_adapter, capsys):
    path, out = _write(tmp_path, CONDUCTORS), tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--quiet"]) == 0
    for name in ("results.csv", "sweep.png", "sweep.svg", "summary.json", "experiment.json"):
        assert (out / name).stat().st_size > 0
    rows = _rows(out)
    assert [rows[p]["source.material"] for p in sorted(rows)] == ["Au", "Cu", "Cr", "Ag"]
    # Copper and chromium: Ward reproduces the AS lobe closely; copper stays red. (Copper's red
    # channel needs a Ward reflectance right at 1, where the safeguard starts: flagged or not.)
    assert rows["00-002"]["target.reliable"] == "True"
    for p in ("00-001", "00-002"):
        assert float(rows[p]["target.relative_rmse"]) < 0.03
    assert float(rows["00-001"]["target.specular_reflectance_r"]) > 1.5 * float(
        rows["00-001"]["target.specular_reflectance_b"])
    # Silver needs a Ward reflectance above 1, which Mitsuba 0.5's safeguard trims: flagged, and the
    # row says why. (Gold's red channel sits right at 1.)
    ag = rows["00-003"]
    assert ag["flagged"] == "True" and "trims" in ag["why"] and ag["target.verdict"] == "unreliable"
    assert float(ag["target.energy_scale"]) < 1.0
    assert float(ag["source.reflectivity_r"]) > 0.95
    from brdfremap.core.experiments.table import ExperimentSummary

    summary = json.loads((out / "summary.json").read_text())
    ExperimentSummary.model_validate(summary)  # what `remap schema experiment-summary` publishes
    assert summary["points"] == 4 and summary["flagged"] >= 1 and summary["renders"] > 0
    for p in sorted(rows):
        read_result(out / "points" / p / "result.json")  # every report validates against `remap schema`
    table = _table(out)
    first = capsys.readouterr().out
    assert "points         4" in first

    # Run again: every point is reused (no render), and the outputs are rebuilt the same.
    assert main(["sweep", str(path), "--out", str(out), "--quiet"]) == 0
    again = capsys.readouterr().out
    assert "(4 remaps resumed" in again and "renders        0 target renders" in again
    assert _rows(out) == rows

    # A point made by another version of the engine (another key) is redone, not reused; so is one
    # whose report is of an older format, or whose image no longer matches it.
    doc_path = out / "points/00-002/result.json"
    doc = json.loads(doc_path.read_text())
    assert doc["engine"] and all("jacobians" in st for st in doc["stages"])
    doc_path.write_text(json.dumps({**doc, "key": "0" * 20}))
    (out / "points/00-001/result.json").write_text(json.dumps({k: v for k, v in doc.items() if k != "schema_version"}))
    (out / "points/00-000/target.exr").write_bytes(b"not the image")
    assert main(["sweep", str(path), "--out", str(out), "--quiet"]) == 0
    third = capsys.readouterr().out
    assert "(1 remaps resumed" in third and "renders        0 target renders" not in third
    assert _table(out) == table


def test_a_changed_point_is_rerun_and_the_others_reused(tmp_path, mitsuba_adapter, capsys):
    doc = dict(CONDUCTORS, sweep={"param": "material", "values": ["Au", "Cu"]})
    out = tmp_path / "out"
    assert main(["sweep", str(_write(tmp_path, doc)), "--out", str(out), "--quiet"]) == 0
    capsys.readouterr()
    doc["sweep"] = {"param": "material", "values": ["Au", "Cr"]}  # point 00-001 changes
    assert main(["sweep", str(_write(tmp_path, doc)), "--out", str(out), "--quiet"]) == 0
    assert "(1 remaps resumed" in capsys.readouterr().out
    assert _rows(out)["00-001"]["source.material"] == "Cr"


def test_roundtrip_recovers_the_reflectivity(tmp_path, mitsuba_adapter, capsys):
    doc = dict(CONDUCTORS, kind="roundtrip", name="small Fig. 6",
               sweep={"param": "material", "values": ["Au", "Cu", "Cr", "Ni_palik"]},
               back={"adapter": "mitsuba", "model": "ashikhmin_shirley", "fix": {"material": "reflectivity"}},
               compare="reflectivity",
               plot={"x": "source.reflectivity", "y": "back.reflectivity", "channels": "each"})
    out = tmp_path / "out"
    assert main(["roundtrip", str(_write(tmp_path, doc)), "--out", str(out), "--quiet"]) == 0
    fit = json.loads((out / "summary.json").read_text())["roundtrip_fit_unflagged"]
    assert fit["points"] >= 9  # 4 materials x 3 channels, less any flagged
    assert abs(fit["slope"] - 1) < 0.05 and fit["r2"] > 0.99 and fit["rms_from_unit_line"] < 0.02
    assert (out / "roundtrip.png").stat().st_size > 0
    assert (out / "points/00-000/back/result.json").exists()
    assert "round trip     slope" in capsys.readouterr().out


def test_local_processes_and_a_dask_cluster_give_the_same_table(tmp_path, mitsuba_adapter, capsys):
    """The same sweep in this process, in two local worker processes (--jobs 2) and on a Dask
    LocalCluster of two worker processes (--scheduler): the same fits, cell for cell."""
    from distributed import LocalCluster

    path = _write(tmp_path, CONDUCTORS)
    assert main(["sweep", str(path), "--out", str(tmp_path / "inline"), "--quiet"]) == 0
    assert main(["sweep", str(path), "--out", str(tmp_path / "pool"), "--quiet", "--jobs", "2"]) == 0
    assert "in up to 2 local processes" in capsys.readouterr().out
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert main(["sweep", str(path), "--out", str(tmp_path / "dask"), "--quiet",
                     "--scheduler", cluster.scheduler_address]) == 0
    assert f"in dask at {cluster.scheduler_address} (2 workers)" in capsys.readouterr().out
    inline = _table(tmp_path / "inline")
    assert len(inline) == 4 and _table(tmp_path / "pool") == inline and _table(tmp_path / "dask") == inline
    for d in ("pool", "dask"):
        for p in sorted(os.listdir(tmp_path / d / "points")):
            read_result(tmp_path / d / "points" / p / "result.json")


def test_a_sweep_killed_with_kill_9_resumes_with_every_point_once(tmp_path, mitsuba_adapter):
    """SIGKILL halfway (no handler runs, nothing is cleaned up): the rerun reuses every point that
    was stored, runs only the others, and ends with each point once and complete."""
    doc = dict(CONDUCTORS, sweep={"param": "material", "values": ["Au", "Cu", "Cr", "Ag", "Al", "Ni_palik", "W",
                                                                  "Mo", "Ta", "Rh", "Ir", "Hg"]})
    path, out = _write(tmp_path, doc), tmp_path / "out"
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "sweep", str(path), "--out", str(out), "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not (out / "points/00-004/result.json").exists():
        assert proc.poll() is None and time.time() < deadline, proc.communicate()
        time.sleep(0.02)
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    done = {p for p in os.listdir(out / "points") if (out / "points" / p / "result.json").exists()}
    assert 5 <= len(done) < 12, done
    rerun = subprocess.run(cmd[:-1], capture_output=True, text=True, timeout=300)  # with its progress lines
    assert rerun.returncode == 0, rerun.stderr
    assert f"({len(done)} remaps resumed" in rerun.stdout  # nothing done twice
    ran = [line for line in rerun.stderr.splitlines() if line.startswith("[")]
    assert sum("[resumed]" not in line for line in ran) == 12 - len(done)
    assert len(_rows(out)) == 12
    for p in os.listdir(out / "points"):
        assert not [f for f in os.listdir(out / "points" / p) if f.startswith(".staging")]
        read_result(out / "points" / p / "result.json")


def test_an_interrupted_sweep_resumes(tmp_path, mitsuba_adapter):
    """Ctrl-C mid-sweep: exit 130 without a traceback; the rerun reuses the finished points."""
    doc = dict(CONDUCTORS, sweep={"param": "material", "values": ["Au", "Cu", "Cr", "Ag", "Al", "Ni_palik", "W",
                                                                  "Mo", "Ta", "Rh", "Ir", "Hg"]})
    path, out = _write(tmp_path, doc), tmp_path / "out"
    cmd = [sys.executable, "-c", "import sys; from brdfremap.core.cli import main; sys.exit(main())",
           "sweep", str(path), "--out", str(out), "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not (out / "points/00-002/result.json").exists():
        assert proc.poll() is None and time.time() < deadline, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err and "interrupted" in err, err
    assert not (out / "results.csv").exists()
    done = sum((out / "points" / p / "result.json").exists() for p in os.listdir(out / "points"))
    assert 3 <= done < 12
    rerun = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert f"({done} remaps resumed" in rerun.stdout
    assert len(_rows(out)) == 12
