"""Processes that die, are killed or misbehave: real signals, real worker processes (docs/reliability.md)."""

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.run.workerproc import JsonLinesWorker
from helpers import MATERIALS, SmallFilesystem, fill, one_line_error, remap

DATA = Path(__file__).resolve().parents[1] / "data" / "renderers"
SLOW_START = textwrap.dedent("""
    import json, sys, time
    time.sleep(1.5)  # a renderer's start-up
    print(json.dumps({"ok": True}), flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        print(json.dumps({"id": req["id"], "ok": True}), flush=True)
""")


def _kill_while_starting(worker: JsonLinesWorker) -> dict:
    """Send a request; kill -9 the worker while it is still starting (before its greeting)."""
    answer: dict = {}
    t = threading.Thread(target=lambda: answer.update(worker.request({"op": "ping"})))
    t.start()
    deadline = time.time() + 30
    while worker.proc is None and time.time() < deadline:
        time.sleep(0.005)
    assert worker.proc is not None and not worker.hello, "the worker greeted before it could be killed"
    os.kill(worker.proc.pid, signal.SIGKILL)
    t.join(timeout=120)
    return answer


def test_a_worker_killed_during_its_start_up_is_restarted_once():
    """Case 7: the start was outside the retry, so a worker killed while starting failed the render."""
    w = JsonLinesWorker([sys.executable, "-c", SLOW_START], name="slow")
    try:
        assert _kill_while_starting(w).get("ok") is True and w.restarts == 1 and w.alive()
    finally:
        w.close()


def test_a_worker_started_from_a_thread_that_ends_lives_on():
    """Linux's parent-death signal follows the thread that forked: a worker started from a request's
    thread was killed when that thread ended (found as a flaky case 7 under load)."""
    w = JsonLinesWorker([sys.executable, "-c", SLOW_START.replace("time.sleep(1.5)", "pass")], name="threaded")
    try:
        t = threading.Thread(target=lambda: w.request({"op": "ping"}))
        t.start()
        t.join(timeout=60)
        time.sleep(0.5)
        assert w.alive()
    finally:
        w.close()


def test_a_blender_worker_killed_during_its_start_up_is_restarted(cycles_adapter):
    """Case 7 with the real Blender worker."""
    from brdfremap.adapters.cycles.adapter import CyclesAdapter

    adapter = CyclesAdapter()
    try:
        assert _kill_while_starting(adapter.worker).get("ok") is True and adapter.worker.restarts == 1
        img = adapter.render("diffuse", adapter.models["diffuse"].complete({}), ProbeScene(resolution=16, spp=4))
        assert img.max() > 0
    finally:
        adapter.close()


def _sweep(tmp_path, n=16, resolution=128):
    values = ["Au", "Cu", "Cr", "Ag", "Al", "W", "Mo", "Ta", "Rh", "Ir", "Hg", "Li", "K", "Nb", "Be", "TiN"][:n]
    exp = tmp_path / "exp.yaml"
    exp.write_text("kind: sweep\nname: t\nsource: {adapter: mitsuba, model: ashikhmin_shirley, params: {alpha: 0.2}}\n"
                   f"sweep: {{param: material, values: [{', '.join(values)}]}}\n"
                   "target: {adapter: mitsuba, model: ward, fix: {diffuse_reflectance: 0.0}}\n"
                   f"scene: {{resolution: {resolution}}}\nplot: {{x: source.reflectivity, y: target.alpha}}\n")
    return exp


def _children(pid: int) -> list[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    return [int(p) for p in out]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except (ProcessLookupError, FileNotFoundError):
        return False


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_sweep_on_local_processes_killed_leaves_no_worker_behind(tmp_path, sig, mitsuba_adapter):
    """kill -9 (no handler runs) and SIGTERM of `remap sweep --jobs 2`: its worker processes exit
    (each watches its parent); SIGTERM exits 143 like Ctrl-C does, keeping what was stored."""
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "sweep", str(_sweep(tmp_path)), "--out", str(out), "--jobs", "2",
           "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not list((out / "points").glob("*/result.json")) if (out / "points").exists() else True:
        assert proc.poll() is None and time.time() < deadline, proc.communicate()
        time.sleep(0.05)
    workers = [p for p in _children(proc.pid) if _alive(p)]
    assert workers, "no worker processes to watch"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    if sig == signal.SIGTERM:
        assert proc.returncode == 143 and "remap: terminated" in err and "Traceback" not in err, err
    deadline = time.time() + 15
    while any(_alive(p) for p in workers) and time.time() < deadline:
        time.sleep(0.2)
    assert not [p for p in workers if _alive(p)], "worker processes outlived remap"
    rerun = remap("sweep", _sweep(tmp_path), "--out", out, "--quiet")
    assert rerun.returncode == 0 and "remaps resumed" in rerun.stdout, rerun.stderr


def test_sigterm_stops_a_sweep_whose_workers_are_mid_render(tmp_path):
    """Third trial N9: SIGTERM to `remap sweep --jobs 2` while both workers waited on a slow
    renderer printed "terminated" and went on: the interpreter joined the workers at exit, and
    they stopped only once it was gone. The workers are ended now, not waited for."""
    defs = tmp_path / "defs"
    defs.mkdir()
    text = (DATA / "fake-oneshot.yaml").read_text().replace("{here}", str(DATA)).replace("timeout: 5", "timeout: 120")
    (defs / "slow.yaml").write_text(text.replace("name: fake-oneshot", "name: slow"))
    exp = tmp_path / "exp.yaml"
    exp.write_text("kind: sweep\nname: hang\nsource: {adapter: mitsuba, model: diffuse}\n"
                   "sweep: {param: reflectance, values: [0.2, 0.5, 0.7]}\n"
                   "target: {adapter: slow, model: lambert, fix: {fault: hang}}\n"
                   "scene: {resolution: 16, spp: 4}\nplot: {x: source.reflectance, y: target.albedo}\n")
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "sweep", str(exp), "--out", str(tmp_path / "o"), "--jobs", "2",
           "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "BRDFREMAP_RENDERERS": str(defs)})
    deadline = time.time() + 60
    while len([p for p in _children(proc.pid) if _alive(p)]) < 2 or not _renderers_started(proc.pid):
        assert proc.poll() is None and time.time() < deadline, proc.communicate()
        time.sleep(0.2)
    t0 = time.time()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and time.time() - t0 < 20, err


def _renderers_started(pid: int) -> bool:
    """Whether a grandchild of ``pid`` (a renderer a pool worker started) is running."""
    return any(_children(w) for w in _children(pid))


def test_a_scratch_folder_of_a_killed_process_is_removed_by_the_next_one(tmp_path):
    """Case 10: /dev/shm scratch folders stayed after kill -9; each is named after its process,
    and the next adapter to start removes those whose process is gone."""
    from brdfremap.adapters.subprocess.adapter import adapter_class

    env = {**os.environ, "BRDFREMAP_SCRATCH": str(tmp_path)}
    child = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        from brdfremap.adapters.subprocess.adapter import adapter_class
        a = adapter_class({str(DATA / 'fake-oneshot.yaml')!r})()
        print(a.work, flush=True)
        import time; time.sleep(60)
    """)], stdout=subprocess.PIPE, text=True, env=env)
    left = Path(child.stdout.readline().strip())
    child.kill()
    child.wait()
    child.stdout.close()
    assert left.is_dir() and left.parent == tmp_path
    os.environ["BRDFREMAP_SCRATCH"] = str(tmp_path)
    try:
        a = adapter_class(DATA / "fake-oneshot.yaml")()
        assert not left.exists() and a.work.is_dir()
        a.close()
        assert not a.work.exists()
    finally:
        del os.environ["BRDFREMAP_SCRATCH"]


def test_an_external_renderer_with_its_scratch_filesystem_full_is_one_line(tmp_path):
    """Case 8: a full /dev/shm gave a traceback; the scratch folder is where $BRDFREMAP_SCRATCH says."""
    with SmallFilesystem(tmp_path / "shm", "256k") as shm:
        if shm is None:
            pytest.skip("cannot mount a tmpfs here (needs root)")
        mat = tmp_path / "m.yaml"
        mat.write_text("adapter: mitsuba\nmodel: diffuse\nparams: {reflectance: 0.5}\n")
        fill(shm, leave=0)
        proc = remap("--adapter", DATA / "fake-oneshot.yaml", "--model", "lambert", "--source", mat, "--out",
                     tmp_path / "o", "--resolution", "16", "--quiet", env={"BRDFREMAP_SCRATCH": str(shm)})
        one_line_error(proc, "No space left on device")


def test_a_chatty_persistent_renderer_is_answered_by_id():
    """Case 12: a stray JSON line on stdout was taken for the answer; answers are matched by id."""
    from brdfremap.adapters.subprocess.adapter import adapter_class

    a = adapter_class(DATA / "fake-persistent.yaml")()
    try:
        img = a.render("lambert", a.models["lambert"].complete({"fault": "stray"}), ProbeScene(resolution=16))
        assert img.max() > 0
    finally:
        a.close()


def test_duplicate_and_broken_renderer_definitions_break_nothing_else(tmp_path, mitsuba_adapter):
    """Case 6: one duplicate definition broke every command, naming neither file."""
    folder = tmp_path / "renderers"
    folder.mkdir()
    text = (DATA / "fake-oneshot.yaml").read_text()
    (folder / "a.yaml").write_text(text.replace("fake_renderer.py", str(DATA / "fake_renderer.py")))
    (folder / "b.yaml").write_text(text.replace("fake_renderer.py", str(DATA / "fake_renderer.py")))
    (folder / "typo.yaml").write_text('name: typo\ncomand: ["x"]\nmodels: {}\n')
    (folder / "gold.yaml").write_text((MATERIALS / "gold.yaml").read_text())  # a material kept there: skipped
    env = {"BRDFREMAP_RENDERERS": str(folder)}
    listed = remap("adapters", env=env)
    assert listed.returncode == 0, listed.stderr
    assert f"defined twice, in {folder / 'a.yaml'} and {folder / 'b.yaml'}" in listed.stdout
    assert "comand: unknown field" in listed.stdout and "gold" not in listed.stdout.split("mitsuba  [")[0]
    one_line_error(remap("--adapter", "fake-oneshot", "--model", "lambert", "--source", MATERIALS / "gold.yaml",
                         "--out", tmp_path / "o", env=env), "defined twice")
    ok = remap("--adapter", "mitsuba", "--model", "roughconductor", "--source", MATERIALS / "gold.yaml", "--out",
               tmp_path / "o2", "--resolution", "32", "--quiet", env=env)
    assert ok.returncode == 0, ok.stderr


def test_a_scheduler_address_that_is_not_dask_is_one_line(tmp_path):
    """A mistyped --scheduler port on a web server hung the client, or crashed it."""
    import socket

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()  # accepts, and never says a word (as an HTTP server waiting for a request)
    port = server.getsockname()[1]
    try:
        proc = remap("sweep", _sweep(tmp_path, 2, 32), "--out", tmp_path / "o", "--scheduler",
                     f"tcp://127.0.0.1:{port}", timeout=60)
        one_line_error(proc, "not a Dask scheduler")
        server.close()
        one_line_error(remap("sweep", _sweep(tmp_path, 2, 32), "--out", tmp_path / "o", "--scheduler",
                             f"tcp://127.0.0.1:{port}"), "cannot reach the Dask scheduler")
    finally:
        server.close()


def test_a_bundles_configs_renderers_folder_runs_nothing(tmp_path):
    """Case 2 again: definitions are not read from the current folder, so a downloaded bundle with
    configs/renderers/evil.yaml naming `adapter: shiny` cannot choose a program."""
    bundle = tmp_path / "bundle"
    (bundle / "configs" / "renderers").mkdir(parents=True)
    pwned = tmp_path / "PWNED"
    (bundle / "configs" / "renderers" / "evil.yaml").write_text(
        f'name: shiny\ncommand: ["sh", "-c", "id > {pwned}; exit 1", "{{output}}"]\n'
        "models: {metal: {parameters: [{name: a, kind: scalar, default: 0.5}]}}\n")
    (bundle / "brass.yaml").write_text("adapter: shiny\nmodel: metal\n")
    for args in (["render", "brass.yaml", "--out", "x.exr"],
                 ["--source", "brass.yaml", "--adapter", "mitsuba", "--model", "diffuse", "--out", "o"]):
        one_line_error(remap(*args, cwd=bundle), "unknown adapter 'shiny'")
    assert not pwned.exists()


@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143), (signal.SIGHUP, 129),
                                         (signal.SIGKILL, -9)])
def test_an_external_renderer_stops_with_remap(tmp_path, sig, status):
    """Case 10: the renderer (and its helper) outlived remap on every signal; now it is killed with
    its process group on Ctrl-C, SIGTERM and SIGHUP, and by the kernel when remap is killed."""
    mat = tmp_path / "m.yaml"
    mat.write_text("adapter: mitsuba\nmodel: diffuse\n")
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "--adapter", str(DATA / "fake-oneshot.yaml"), "--model",
           "lambert", "--source", str(mat), "--out", str(tmp_path / "o"), "--fix", "fault=hang", "--resolution", "16"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline, renderer = time.time() + 60, None
    while renderer is None and time.time() < deadline:
        found = subprocess.run(["pgrep", "-f", "fake_renderer.py"], capture_output=True, text=True).stdout.split()
        renderer = int(found[0]) if found else None
        time.sleep(0.05)
    assert renderer is not None, proc.communicate()
    time.sleep(0.3)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == status and "Traceback" not in err, (proc.returncode, err)
    deadline = time.time() + 10
    while _alive(renderer) and time.time() < deadline:
        time.sleep(0.1)
    alive = _alive(renderer)
    # After kill -9 the kernel kills the renderer itself; a helper it started (the fake's sleep)
    # is the renderer's to stop, and is cleaned up here so that it does not outlive the test.
    subprocess.run(["pkill", "-f", "import time; time.sleep\\(120\\)"], capture_output=True)
    assert not alive, "the renderer outlived remap"


@pytest.mark.parametrize("sig, status, said", [(signal.SIGTERM, 143, "terminated"), (signal.SIGHUP, 129, "terminated"),
                                               (signal.SIGINT, 130, "interrupted")])
def test_a_signal_mid_fit_gives_its_own_exit_status(tmp_path, sig, status, said, mitsuba_adapter):
    """SIGTERM during a Mitsuba remap said 'interrupted' and exited 130 (the renderer turned it into
    a KeyboardInterrupt); the signal that came decides."""
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "--adapter", "mitsuba", "--model", "principled", "--source",
           str(MATERIALS / "gold.yaml"), "--out", str(tmp_path / "o"), "--resolution", "128", "--spp", "2048",
           "--coarse", "0", "--start", "defaults"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while not (tmp_path / "o" / ".lock").exists() and time.time() < deadline:
        time.sleep(0.02)
    time.sleep(1.5)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status and f"remap: {said}" in err and "Traceback" not in err, (proc.returncode, err)


def test_a_definition_taking_an_installed_adapters_name_breaks_nothing(tmp_path, mitsuba_adapter):
    folder = tmp_path / "renderers"
    folder.mkdir()
    (folder / "m.yaml").write_text((DATA / "fake-oneshot.yaml").read_text().replace("name: fake-oneshot",
                                                                                  "name: mitsuba"))
    env = {"BRDFREMAP_RENDERERS": str(folder)}
    listed = remap("adapters", env=env)
    assert f"renderer definition {folder / 'm.yaml'}: its name 'mitsuba' is an installed adapter's" in listed.stdout
    ok = remap("render", MATERIALS / "gold.yaml", "--out", tmp_path / "x.exr", "--resolution", "16", "--quiet",
               env=env)
    assert ok.returncode == 0, ok.stderr
