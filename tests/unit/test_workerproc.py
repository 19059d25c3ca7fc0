"""The persistent JSON-lines worker: faults become RenderErrors with the worker's stderr."""

import sys
import textwrap

import pytest

from brdfremap.core.data.errors import RenderError
from brdfremap.core.run.workerproc import JsonLinesWorker

ECHO = textwrap.dedent("""
    import json, sys, os
    print(json.dumps({"ok": True, "pid": os.getpid()}), flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        if req["op"] == "quit":
            break
        if req["op"] == "die":
            print("about to die", file=sys.stderr, flush=True)
            os._exit(7)
        if req["op"] == "hang":
            import time; time.sleep(60)
        if req["op"] == "noise":
            print("renderer chatter on stdout", flush=True)
        if req["op"] == "fail":
            print(json.dumps({"id": req["id"], "ok": False, "error": "bad parameter"}), flush=True)
            continue
        print(json.dumps({"id": req["id"], "ok": True, "echo": req.get("x")}), flush=True)
""")


def _worker(**kw):
    return JsonLinesWorker([sys.executable, "-c", ECHO], name="echo", **kw)


def test_requests_are_answered_and_stray_stdout_is_ignored():
    w = _worker()
    try:
        assert w.request({"op": "echo", "x": 5})["echo"] == 5
        assert w.request({"op": "noise"})["ok"]
    finally:
        w.close()
    assert not w.alive()


def test_an_error_answer_is_a_render_error():
    w = _worker()
    try:
        with pytest.raises(RenderError, match="echo: bad parameter"):
            w.request({"op": "fail"})
        assert w.request({"op": "echo", "x": 1})["echo"] == 1  # still usable
    finally:
        w.close()


def test_a_worker_that_dies_is_restarted_once_then_reported_with_stderr():
    w = _worker()
    try:
        with pytest.raises(RenderError) as e:
            w.request({"op": "die"})  # dies, restarted, dies again
        assert "exited (code 7)" in str(e.value) and "about to die" in str(e.value)
        assert w.restarts == 1
        assert w.request({"op": "echo", "x": 2})["echo"] == 2
    finally:
        w.close()


def test_a_hung_worker_is_killed_at_the_timeout():
    w = _worker(request_timeout=1.0)
    try:
        with pytest.raises(RenderError, match="no answer to hang within 1 s"):
            w.request({"op": "hang"})
        assert not w.alive()
    finally:
        w.close()


def test_a_worker_that_cannot_start():
    w = JsonLinesWorker([sys.executable, "-c", "import sys; print('boom', file=sys.stderr); sys.exit(3)"],
                        name="broken")
    with pytest.raises(RenderError, match="broken: worker exited \\(code 3\\) during start"):
        w.request({"op": "echo"})
    w2 = JsonLinesWorker(["/nonexistent/renderer"], name="missing")
    with pytest.raises(RenderError, match="cannot start"):
        w2.request({"op": "echo"})
