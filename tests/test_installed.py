"""The package as a user meets it: the README's Python example, run as written, and a wheel
(not editable) in a fresh virtual environment, used from a folder outside the repository,
where built-in presets, scene files and studies must be found and a local ``configs/`` must
override them.

Every run here shares one jaxrender cache (references, and compiled programs where a cache is
on), so what the README example renders, the installed command line loads."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "jaxrender"

STUDY = """
name = "outside"
resolution = "16x16"
metrics = ["psnr"]
[[scenes]]
name = "courtyard"
[[paths]]
preset = "pan_slow"
frames = 1
[reference]
pipeline = "reference"
params = { k = 1 }
[timing]
warmup = 0
repeats = 1
single_frame = false
# The times are not the subject: one program per variant, its counts and views timed too.
outputs = "all"
[[pipelines]]
preset = "dacs_threshold_sweep"
"""

LOCAL_PAN = """
description = "a local pan that overrides the built-in"
type = "pan"
frames = 3
[params]
pixels_per_frame = 2.0
"""


def run(args, cwd, env, timeout=900):
    done = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)
    assert done.returncode == 0, (f"{' '.join(map(str, args))} failed ({done.returncode}):\n"
                                  f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
    return done.stdout


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("cache")


def readme_python_example() -> str:
    text = (REPO / "README.md").read_text()
    section = text.split("\n## In Python\n", 1)[1]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


def test_readme_python_example_runs_as_written(installed, tmp_path):
    # In a fresh interpreter of the installed wheel, from a folder outside the repository, as a
    # user runs it (not in this long-lived test worker: a worker that had compiled hundreds of
    # programs crashed once inside XLA:CPU's compiler while the example compiled its own).
    # Its last line runs the bundled quickstart by name, so this is also the check that a
    # bundled study resolves from anywhere and writes under the working directory.
    bin_dir, env = installed
    script = tmp_path / "readme_example.py"
    script.write_text(readme_python_example() + CHECKS)
    printed = run([bin_dir / "python", str(script)], cwd=tmp_path, env=env)
    found = json.loads(printed.rsplit("CHECKS ", 1)[1])
    assert found["shape"] == [8, 72, 128, 3], found
    assert math.isfinite(found["psnr"]) and found["psnr"] > 10, found
    assert found["rows"] and (tmp_path / "runs/quickstart/results.csv").is_file(), found
    assert Path(found["module"]).is_relative_to(bin_dir.parent), found
    assert re.search(r"\d+ shaded pixels, \d+\.\d dB", printed), printed


# What the README example must have made, printed after it as one JSON line.
CHECKS = """
import json as _json
print("CHECKS " + _json.dumps({"shape": list(frames.image.shape), "psnr": float(psnr),
                                "rows": len(run.rows), "module": jaxrender.__file__}))
"""


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(out),
         str(REPO)], cwd=out, env=os.environ.copy())
    (built,) = out.glob("jaxrender-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel, shared_cache, tmp_path_factory):
    """A fresh venv holding the wheel; its dependencies come from this interpreter's
    site-packages, appended to its path (a .pth line adds the folder without running the
    editable install's hooks in it, so the checkout itself is not importable there)."""
    venv = tmp_path_factory.mktemp("venv")
    run([sys.executable, "-m", "venv", str(venv)], cwd=venv, env=os.environ.copy())
    bin_dir = venv / "bin"
    site = Path(subprocess.check_output(
        [bin_dir / "python", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        text=True).strip())
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    run([bin_dir / "python", "-m", "pip", "install", "--no-deps", "--no-index", "--quiet",
         str(wheel)], cwd=venv, env=os.environ.copy())
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["JAXRENDER_CACHE"] = str(shared_cache)
    return bin_dir, env


def test_wheel_holds_the_presets_scenes_and_studies(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    shipped = sorted(str(p.relative_to(REPO)) for folder in ("configs", "studies")
                     for p in (PACKAGE / folder).rglob("*.toml"))
    assert len(shipped) >= 10, f"too few built-in files found in the checkout: {shipped}"
    missing = [p for p in shipped if p not in names]
    assert not missing, f"the wheel {wheel.name} lacks {missing}"


def test_installed_package_imports_from_its_venv(installed, tmp_path):
    bin_dir, env = installed
    where = run([bin_dir / "python", "-c", "import jaxrender; print(jaxrender.__file__)"],
                cwd=tmp_path, env=env).strip()
    assert Path(where).is_relative_to(bin_dir.parent), (
        f"jaxrender imported from {where}, not from the fresh venv {bin_dir.parent}")


def test_bundled_studies_are_listed_and_resolve_by_name(installed, tmp_path):
    # Running one by name is the README example's last line (above); the command line
    # resolves the same names.
    bin_dir, env = installed
    listing = run([bin_dir / "jaxrender", "studies"], cwd=tmp_path, env=env)
    assert "quickstart" in listing, listing
    checked = run([bin_dir / "jaxrender", "validate", "quickstart"], cwd=tmp_path, env=env)
    assert "quickstart: ok" in checked, checked
    assert not (tmp_path / "runs").exists(), "validate wrote a run folder"


def test_builtin_presets_then_a_local_override(installed, tmp_path):
    bin_dir, env = installed
    (tmp_path / "outside.toml").write_text(STUDY)
    run([bin_dir / "jaxrender", "validate", "outside.toml"], cwd=tmp_path, env=env)
    run([bin_dir / "jaxrender", "study", "outside.toml", "--out", "runs/outside",
         "--no-figures"], cwd=tmp_path, env=env)
    resolved = (tmp_path / "runs/outside/study.toml").read_text()
    assert "# preset 'pan_slow': built-in (" in resolved, resolved
    assert "# preset 'dacs_threshold_sweep': built-in (" in resolved, resolved

    (tmp_path / "configs/paths").mkdir(parents=True)
    local = tmp_path / "configs/paths/pan_slow.toml"
    local.write_text(LOCAL_PAN)
    listing = run([bin_dir / "jaxrender", "presets"], cwd=tmp_path, env=env)
    line = next(ln for ln in listing.splitlines() if "pan_slow" in ln)
    assert str(local.resolve()) in line, f"`jaxrender presets` says: {line}"
    log = run([bin_dir / "jaxrender", "study", "outside.toml", "--out", "runs/local",
               "--no-progress", "--no-figures"], cwd=tmp_path, env=env)
    resolved = (tmp_path / "runs/local/study.toml").read_text()
    assert (f"# preset 'pan_slow': {(tmp_path / 'configs').resolve()} ({local.resolve()}, "
            "overrides the built-in)") in resolved, resolved
    assert "pixels_per_frame = 2.0" in resolved, resolved
    assert "compiled or loaded 5 program(s)" in log, log
    # Where a cache is on (a GPU, or JAXRENDER_COMPILATION_CACHE=1) the camera override reuses
    # every program of the first run, as cameras are arguments (test_executables checks the
    # key itself); on the CPU default nothing is cached and the log claims nothing.
    cached = re.search(r"(executable store|compilation cache): \d+ loaded, (\d+) compiled", log)
    assert cached is None or cached.group(2) == "0", log
