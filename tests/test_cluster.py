"""Runs on a real Dask cluster from the command line: a ``dask scheduler`` and two ``dask worker``
processes on localhost, ``sweep``, ``place --map`` and ``team --sweep-heading`` through ``--dask
tcp://...`` with one worker killed while it runs a task, and the files compared with the serial
run's byte for byte. An unreachable scheduler is refused in one line, in time."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shared_texts import grid_site

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "PYTHONUNBUFFERED": "1"}

SWEEP = ["sweep", "planar_dual_arm", "--angle", "0:360:181", "--distance", "0.6:1.4:9", "--heading", "0:315:8",
         "--chunk-size", "64", "--no-progress"]  # fmt: skip
PLACE = ["place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "kinematic:capacity:+x",
         "--map-cells", "9", "--no-progress"]  # fmt: skip
TEAM = ["team", str(ROOT / "examples" / "beam_team.toml"), "--polytope", "--sweep-heading=-40:40:17", "--no-progress"]
PAYLOAD = ["payload", "planar_dual_arm", "--map", "--angle=-60:60:9", "--distance", "0.3:0.9:9", "--accel", "1,0",
           "--mu", "0.5"]  # fmt: skip


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def cli(args, **kwargs) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mobmanip", *args], env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kwargs)  # fmt: skip


def finish(process: subprocess.Popen, timeout: float = 120) -> str:
    out, err = process.communicate(timeout=timeout)
    assert process.returncode == 0, err
    return out


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """(address, {name: worker process}) of a scheduler and two single-threaded workers."""
    log = tmp_path_factory.mktemp("dask")
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    processes = [
        subprocess.Popen(
            [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
            env=ENV,
            stdout=subprocess.DEVNULL,
            stderr=open(log / "scheduler.log", "w"),
        )  # fmt: skip
    ]
    workers = {}
    for name in ("w1", "w2"):
        workers[name] = subprocess.Popen(
            [str(BIN / "dask"), "worker", address, "--name", name, "--nthreads", "1", "--no-nanny",
             "--no-dashboard"], env=ENV, stdout=subprocess.DEVNULL, stderr=open(log / f"{name}.log", "w"),
        )  # fmt: skip
        processes.append(workers[name])
    try:
        with distributed.Client(address, timeout=30) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for process in processes[::-1]:
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
        for process in processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()


def run_killing(address: str, workers: dict, victim: str, args: list[str]) -> str:
    """Run the command on the cluster and kill worker ``victim`` once it is running one of its tasks."""
    process = cli(args)
    with distributed.Client(address, timeout=30) as client:
        deadline = time.monotonic() + 120
        killed = False
        while not killed and process.poll() is None and time.monotonic() < deadline:
            info = client.scheduler_info()["workers"]
            busy = client.processing()
            for worker, tasks in busy.items():
                if info.get(worker, {}).get("name") == victim and tasks:
                    workers[victim].kill()
                    workers[victim].wait()
                    killed = True
            time.sleep(0.005)
    out = finish(process)
    assert killed, f"{victim} ran no task of {args[0]} before it finished: nothing was tested"
    return out


def test_sweep_and_map_on_a_cluster_survive_a_killed_worker(cluster, tmp_path):
    address, workers = cluster
    serial = [cli([*SWEEP, "--workers", "1", "-o", str(tmp_path / "serial")]),
              cli([*PLACE, "--map", str(tmp_path / "serial_map")])]  # fmt: skip
    for process in serial:
        finish(process)
    run_killing(address, workers, "w1", [*SWEEP, "--dask", address, "-o", str(tmp_path / "dask")])
    assert (tmp_path / "dask" / "sweep.csv").read_bytes() == (tmp_path / "serial" / "sweep.csv").read_bytes()
    # the remaining worker alone (a lost one is not needed), killed one mid-task, restarted as w1
    workers["w1"] = subprocess.Popen(
        [str(BIN / "dask"), "worker", address, "--name", "w1b", "--nthreads", "1", "--no-nanny", "--no-dashboard"],
        env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    with distributed.Client(address, timeout=30) as client:
        client.wait_for_workers(2, timeout=60)
    out = run_killing(address, workers, "w2", [*PLACE, "--map", str(tmp_path / "dask_map"), "--dask", address])
    assert "map: " in out
    for name in ("map.csv", "map.npz"):
        assert (tmp_path / "dask_map" / name).read_bytes() == (tmp_path / "serial_map" / name).read_bytes(), name


def test_a_team_sweep_on_a_cluster_survives_a_killed_worker(cluster, tmp_path):
    address, workers = cluster
    serial = cli([*TEAM, "--json", str(tmp_path / "serial.json"), "--plot", str(tmp_path / "serial.png")])
    # a worker of its own to kill, whatever the earlier tests left of the cluster's two
    workers["team"] = subprocess.Popen(
        [str(BIN / "dask"), "worker", address, "--name", "team", "--nthreads", "1", "--no-nanny", "--no-dashboard"],
        env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    with distributed.Client(address, timeout=30) as client:
        client.wait_for_workers(1 + sum(w.poll() is None for n, w in workers.items() if n != "team"), timeout=60)
    out = finish(serial)
    dask = [*TEAM, "--json", str(tmp_path / "dask.json"), "--plot", str(tmp_path / "dask.png"), "--dask", address]
    out_dask = run_killing(address, workers, "team", dask)
    assert "heading sweep: " in out_dask
    assert out_dask.replace("dask.", "serial.") == out  # the same report, line by line
    for name in ("json", "png"):
        assert (tmp_path / f"dask.{name}").read_bytes() == (tmp_path / f"serial.{name}").read_bytes(), name


SITE = grid_site(starts=2, x_count=3)


def test_site_on_a_cluster_equals_the_serial_run(cluster, tmp_path):
    address, _ = cluster
    (tmp_path / "shelf.toml").write_text(SITE)
    finish(cli(["site", str(tmp_path / "shelf.toml"), "-o", str(tmp_path / "serial"), "--no-progress"]))
    out = finish(cli(["site", str(tmp_path / "shelf.toml"), "-o", str(tmp_path / "dask"), "--dask", address]))
    assert "6 of 6 positions placed" in out
    assert (tmp_path / "dask" / "site.csv").read_bytes() == (tmp_path / "serial" / "site.csv").read_bytes()
    assert (tmp_path / "dask" / "site.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_payload_map_on_a_cluster_equals_the_serial_run(cluster, tmp_path):
    address, _ = cluster
    serial = finish(cli([*PAYLOAD, "--out", str(tmp_path / "serial")]))
    dask = finish(cli([*PAYLOAD, "--out", str(tmp_path / "dask"), "--dask", address]))
    assert dask.replace("dask", "serial") == serial  # the same report
    assert "81 object positions (81 bounded)" in serial
    for name in ("payload_map.csv", "payload_map.json"):
        assert (tmp_path / "dask" / name).read_bytes() == (tmp_path / "serial" / name).read_bytes(), name


@pytest.mark.parametrize(
    "command", [SWEEP, [*PLACE, "--map", "MAP"], [*TEAM, "--json", "team.json"], [*PAYLOAD, "--out", "pmap"]]
)
def test_an_unreachable_scheduler_is_refused_in_one_line_within_10_s(command, tmp_path):
    started = time.monotonic()
    process = cli([*command, "--dask", f"tcp://127.0.0.1:{free_port()}"], cwd=tmp_path)
    out, err = process.communicate(timeout=30)
    elapsed = time.monotonic() - started
    assert process.returncode == 2
    assert err.count("\n") == 1 and err.startswith("mobmanip: error: --dask tcp://127.0.0.1:"), err
    assert "cannot reach the Dask scheduler" in err
    assert elapsed < 10
    assert not list(tmp_path.iterdir())  # nothing written


def test_a_malformed_address_is_refused_before_connecting(tmp_path):
    process = cli([*SWEEP, "--dask", "local:0"], cwd=tmp_path)
    _, err = process.communicate(timeout=30)
    assert process.returncode == 2
    assert err.strip() == "mobmanip: error: --dask local:0: local:N needs a worker count N from 1 to 256"
