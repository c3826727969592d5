"""A study spread over several devices: the placement, and on 4 forced CPU devices the same
rows as on one, more than one device used, and an interrupted run resumed without duplicates."""

import json
import os
import subprocess
import sys

import pytest

from jaxrender.errors import UserError
from jaxrender.study import devices

GROUPS = {("a", "x"): 10, ("b", "x"): 10, ("a", "y"): 4, ("c", "z"): 3, ("b", "y"): 1}


def test_assign_balances_frames_heaviest_first():
    got = devices.assign(GROUPS, 2)
    # Hand-worked: a/x -> 0 (10), b/x -> 1 (10), a/y -> 0 (14), c/z -> 1 (13), b/y -> 1 (14).
    assert got == {("a", "x"): 0, ("b", "x"): 1, ("a", "y"): 0, ("c", "z"): 1,
                   ("b", "y"): 1}, got
    assert devices.assign(GROUPS, 1) == dict.fromkeys(GROUPS, 0)
    assert devices.assign(dict(reversed(GROUPS.items())), 2) == got, "order must not matter"


def test_processes_split_the_groups_without_overlap():
    shares = [devices.process_share(GROUPS, i, 3) for i in range(3)]
    flat = [g for s in shares for g in s]
    assert sorted(flat) == sorted(GROUPS) and len(flat) == len(set(flat)), shares


def test_a_device_count_out_of_range_is_refused_naming_the_flag():
    with pytest.raises(UserError, match=r"--devices 9: this process has 1 local device"):
        devices.select_devices(9)
    assert len(devices.select_devices(None)) == len(devices.select_devices(1))


CHILD = r"""
import json, os, sys
import pytest
from jaxrender.study import runner, store
from jaxrender.study.schema import load_study
from tests.study import doubles

mp = pytest.MonkeyPatch()
doubles.install(mp)
study, out = load_study(sys.argv[1]), sys.argv[2]
quiet = lambda *a: None
runner.run_study(study, out + "/one", progress=False, log=quiet, devices=1)
runner.run_study(study, out + "/four", progress=False, log=quiet, devices=4)
# Interrupted after two sequences are stored, then resumed.
real, calls = store.ResultStore.append, []
def stop(self, rows):
    if len(calls) == 2:
        raise KeyboardInterrupt
    calls.append(1)
    real(self, rows)
mp.setattr(store.ResultStore, "append", stop)
try:
    runner.run_study(study, out + "/cut", progress=False, log=quiet, devices=4)
except KeyboardInterrupt:
    pass
mp.setattr(store.ResultStore, "append", real)
resumed = runner.run_study(study, out + "/cut", progress=False, log=quiet, devices=4)
print(json.dumps({"skipped": resumed.skipped, "computed": resumed.computed}))
"""

VARYING = {"time_ms", "time_ms_single", "sequence_ms", "compile_ms", "compile_ms_single",
           "compile_ms_timed", "compile_method", "device_index", "devices"}


def test_four_devices_give_the_rows_of_one(tiny_study, tmp_path):
    from jaxrender.study import store

    script = tmp_path / "child.py"
    script.write_text(CHILD)
    flags = os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=4"
    env = {**os.environ, "JAX_PLATFORMS": "cpu", "PYTHONPATH": os.getcwd(), "XLA_FLAGS": flags}
    done = subprocess.run([sys.executable, str(script), str(tiny_study), str(tmp_path)],
                          capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    resumed = json.loads(done.stdout.strip().splitlines()[-1])
    assert resumed == {"skipped": 2, "computed": 4}, resumed

    def rows(run):
        out = store.read_rows(tmp_path / run / "results.jsonl")
        keyed = {(r["seq"], r["frame"]): json.dumps(
            {k: v for k, v in r.items() if k not in VARYING}, sort_keys=True) for r in out}
        assert len(keyed) == len(out), f"{run}: duplicate rows"
        return keyed, {r["device_index"] for r in out}

    one, used_one = rows("one")
    four, used_four = rows("four")
    cut, _ = rows("cut")
    assert len(one) == 18 and four == one, "4 devices must give the rows of 1, bit for bit"
    assert cut == one, "the resumed run must equal the uninterrupted one"
    assert used_one == {0} and len(used_four) > 1, (used_one, used_four)


PROCESS = r"""
import sys
import pytest
from jaxrender.study import devices, runner
from jaxrender.study.schema import load_study
from tests.study import doubles

doubles.install(pytest.MonkeyPatch())
study_file, out, port, index = sys.argv[1:]
devices.initialize_distributed(f"127.0.0.1:{port}", 2, int(index))
res = runner.run_study(load_study(study_file), out, progress=False, log=lambda *a: None,
                       devices=2)
print(len(res.rows), res.computed)
"""


def test_two_processes_split_a_study_and_merge_its_rows(tiny_study, tmp_path):
    import socket

    from jaxrender.study import store

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    script = tmp_path / "process.py"
    script.write_text(PROCESS)
    flags = os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=2"
    env = {**os.environ, "JAX_PLATFORMS": "cpu", "PYTHONPATH": os.getcwd(), "XLA_FLAGS": flags}
    out = tmp_path / "dist"
    procs = [subprocess.Popen([sys.executable, str(script), str(tiny_study), str(out),
                               str(port), str(i)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env) for i in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    for p, (o, e) in zip(procs, outs):
        assert p.returncode == 0, e[-3000:]
    (rows0, done0), (rows1, done1) = ([int(x) for x in o.split()[-2:]] for o, _ in outs)
    assert done0 + done1 == 6 and done0 > 0 and done1 > 0, "both processes must render"
    assert rows0 == 18, "the first process exports every process's rows"
    stored = store.read_rows(out / "results.jsonl")
    assert len({(r["seq"], r["frame"]) for r in stored}) == len(stored) == 18
    assert (out / "results.csv").is_file()
    assert len({r["device_index"] for r in stored}) > 2, "2 processes x 2 devices"
