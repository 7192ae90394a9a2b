"""The package as users get it: the x86_64 wheel installed alone in a fresh virtual environment
(no Rust toolchain on PATH, no source tree), then the README's quick starts run exactly as
written, and the wheel's tags, licences and version.

The wheel is the one `make wheel` builds (`build/dist`, manylinux2014 through zig); when it is
missing or older than the sources, this module builds it. One environment serves the module:
the base install is checked first, then each quick start's own `pip install` adds its extra.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DIST = ROOT / "build" / "dist"
README = ROOT / "README.md"

pytestmark = pytest.mark.slow


def _wheel() -> Path:
    """The x86_64 wheel, built by `make wheel` when missing or stale."""
    subprocess.run(["make", "-s", "wheel"], cwd=ROOT, check=True, capture_output=True, timeout=1800)
    wheels = sorted(DIST.glob("uasnav-*-manylinux*x86_64*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def wheel() -> Path:
    return _wheel()


class Venv:
    def __init__(self, path: Path, wheel: Path) -> None:
        self.path = path
        self.wheel = wheel
        self.bin = path / "bin"
        # the user's machine: this venv and the system, no cargo/rustc, no source tree
        self.env = {
            k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTHON", "CARGO"))
        }
        self.env["PATH"] = f"{self.bin}:/usr/local/bin:/usr/bin:/bin"
        self.env["HOME"] = os.environ.get("HOME", str(path))

    def run(self, script: str, cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            ["bash", "-euo", "pipefail", "-c", script],
            cwd=cwd,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )

    def pip_install(self, spec: str) -> None:
        p = subprocess.run(
            [str(self.bin / "python"), "-m", "pip", "install", "-q", spec],
            env=self.env,
            capture_output=True,
            text=True,
            timeout=1200,
            check=False,
        )
        assert p.returncode == 0, p.stderr[-3000:]


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory, wheel: Path) -> Venv:
    path = tmp_path_factory.mktemp("fresh") / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(path)], check=True, timeout=300)
    v = Venv(path, wheel)
    v.pip_install(str(wheel))
    return v


def test_base_install_runs_the_base_quick_starts(venv: Venv, tmp_path: Path) -> None:
    """Before any extra is installed: `uasnav --help`, and the quick starts that need no extra
    (`nav`, `allan`, `calibrate` on generated CSV) exactly as the README writes them."""
    assert venv.run("command -v cargo || command -v rustc", tmp_path).returncode != 0
    # the base install holds none of the extras' libraries: no Parquet, no Dask, no web, no F3548
    for mod in ("pyarrow", "fastapi", "distributed", "dask", "uas_standards"):
        p = venv.run(f"python -c 'import {mod}'", tmp_path)
        assert p.returncode != 0 and "ModuleNotFoundError" in p.stderr, (mod, p.stderr)
    p = venv.run("python -c 'import uasnav, uasnav._core; print(uasnav.__file__)'\nuasnav --help", tmp_path)
    assert p.returncode == 0, p.stderr[-3000:]
    assert str(venv.path) in p.stdout.splitlines()[0]  # the installed package, not the tree
    assert "allan" in p.stdout and "nav" in p.stdout
    base = [(title, block) for title, block in quick_starts(README.read_text()) if not PIP.search(block)]
    commands = " ".join(block for _, block in base)
    assert all(f"uasnav {c} " in commands for c in ("nav", "allan", "calibrate")), commands
    for title, block in base:
        folder = tmp_path / title.split(":")[0].replace(" ", "-")
        folder.mkdir()
        p = venv.run(block, folder)
        assert p.returncode == 0, f"{title}\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}"
        assert "error:" not in p.stderr, p.stderr
    assert (tmp_path / "IMU-lab" / "model.json").stat().st_size > 0
    assert (tmp_path / "Navigation-engineer" / "track.csv").stat().st_size > 0


def test_the_installed_wheel_carries_the_geoid(venv: Venv, tmp_path: Path) -> None:
    """Intents (`trajectory intent`, `plan`) take W84 heights from the EGM96 grid shipped in
    the wheel: read from the installed package, it gives the tree's geoid heights."""
    from uasnav.geo.geoid import geoid_height

    code = (
        "import uasnav.geo.geoid as g; from importlib import resources; "
        "print(resources.files('uasnav.geo').joinpath('data', g.GEOID_DATA)); "
        "print(repr(float(g.geoid_height(47.37, 8.54))), repr(float(g.geoid_height(-33.9, 151.2))))"
    )
    p = venv.run(f'python -c "{code}"', tmp_path)
    assert p.returncode == 0, p.stderr[-3000:]
    where, heights = p.stdout.splitlines()[:2]
    assert where.startswith(str(venv.path)), where  # the installed package's grid, not the tree's
    assert [float(h) for h in heights.split()] == [geoid_height(47.37, 8.54), geoid_height(-33.9, 151.2)]


FIELD = '{"type":"Polygon","coordinates":[[[8.54,47.37],[8.544,47.37],[8.544,47.3725],[8.54,47.37]]]}'


NEEDS_EXTRA = {
    "web": "uasnav serve --port 8765",
    "fleet": "uasnav fleet simulate --vehicles 1 --flights 1 --out f",
    "fleet-scan": "mkdir logs\nuasnav fleet scan logs --out s.parquet",
    # Parquet element datasets need pyarrow, from the fleet extra
    "fleet-parquet": "printf 'PAR1' > e.parquet\nuasnav trajectory train e.parquet --out m.json",
    "utm": f"printf '%s' '{FIELD}' > a.geojson\nuasnav plan --area a.geojson --out p",
}


@pytest.mark.parametrize(("case", "command"), sorted(NEEDS_EXTRA.items()), ids=sorted(NEEDS_EXTRA))
def test_missing_extra_names_the_install_line(venv: Venv, tmp_path: Path, case: str, command: str) -> None:
    extra = case.split("-")[0]
    p = venv.run(command, tmp_path)
    assert p.returncode == 1, (p.stdout, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), p.stderr
    assert f"pip install 'uasnav[{extra}]'" in lines[0]
    assert "Traceback" not in p.stderr


def quick_starts(text: str) -> list[tuple[str, str]]:
    """(title, bash block) of every quick start in the README."""
    section = text.split("## Quick starts", 1)[1].split("\n## ", 1)[0]
    found = []
    for part in section.split("\n### ")[1:]:
        title = part.splitlines()[0]
        blocks = re.findall(r"```bash\n(.*?)```", part, flags=re.S)
        assert len(blocks) == 1, title
        found.append((title, blocks[0]))
    return found


def test_readme_is_short_and_has_a_quick_start_per_user() -> None:
    text = README.read_text()
    assert len(text.splitlines()) <= 150
    titles = [t for t, _ in quick_starts(text)]
    assert len(titles) == 5
    for who in ("Navigation engineer", "IMU lab", "Operator", "UTM service", "Fleet analyst"):
        assert any(t.startswith(who) for t in titles), titles
    # the two commands first; CI runs exactly the second
    first = re.search(r"```bash\n(.*?)```", text, flags=re.S)
    assert first is not None
    commands = [line.split("#")[0].strip() for line in first.group(1).splitlines()]
    assert commands == ["make demo", "make test"]
    ci = (ROOT / ".ci" / "run").read_text()
    assert [ln for ln in ci.splitlines() if ln.startswith("make")] == ["make test"]


PIP = re.compile(r"pip install 'uasnav\[(\w+)\]'")
WITH_EXTRA = [t for t, b in quick_starts(README.read_text()) if PIP.search(b)]


@pytest.mark.parametrize("title", WITH_EXTRA)
def test_readme_quick_start_with_an_extra_runs_as_written(venv: Venv, tmp_path: Path, title: str) -> None:
    """The quick starts that install an extra (those without one run in the base test)."""
    block = dict(quick_starts(README.read_text()))[title]
    # `pip install 'uasnav[x]'` takes the extra from the wheel under test, dependencies from PyPI
    script = PIP.sub(lambda m: f"pip install -q '{venv.wheel}[{m.group(1)}]'", block)
    p = venv.run(script, tmp_path, timeout=900)
    assert p.returncode == 0, f"{title}\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}"
    assert "error:" not in p.stderr, p.stderr


def test_wheel_is_portable_abi3_with_licences_and_one_version(wheel: Path) -> None:
    name = wheel.name
    assert "-cp310-abi3-" in name and "manylinux2014_x86_64" in name, name
    cargo = (ROOT / "Cargo.toml").read_text()
    version = re.search(r'\[workspace\.package\][^\[]*?\nversion = "([^"]+)"', cargo, flags=re.S).group(1)
    assert name.startswith(f"uasnav-{version}-")
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        meta = z.read(f"uasnav-{version}.dist-info/METADATA").decode()
    for lic in ("LICENSE-MIT", "LICENSE-APACHE"):
        assert f"uasnav-{version}.dist-info/licenses/{lic}" in names
    assert re.search(r"^Version: " + re.escape(version) + "$", meta, flags=re.M)
    assert re.search(r"^License-Expression: MIT OR Apache-2.0$", meta, flags=re.M)
    # the base requirements hold none of the extras' libraries
    base = [ln for ln in meta.splitlines() if ln.startswith("Requires-Dist:") and "extra ==" not in ln]
    for heavy in ("fastapi", "uvicorn", "dask", "uas-standards", "playwright"):
        assert not any(heavy in ln for ln in base), heavy
    auditwheel = Path(sys.executable).parent / "auditwheel"
    p = subprocess.run([str(auditwheel), "show", str(wheel)], capture_output=True, text=True, check=True)
    assert '"manylinux_2_17_x86_64"' in " ".join(p.stdout.split()), p.stdout


BLOCK_PYARROW = "import sys; sys.modules['pyarrow'] = None; from uasnav.cli import main; main()"


@pytest.mark.parametrize("case", ["fleet-scan", "fleet-parquet"])
def test_parquet_is_the_fleet_extras_in_the_tree(tmp_path: Path, case: str) -> None:
    """The same boundaries in this environment with pyarrow made unimportable (a base install)."""
    import shlex

    prep, command = NEEDS_EXTRA[case].rsplit("\n", 1)
    subprocess.run(["bash", "-c", prep], cwd=tmp_path, check=True)
    argv = shlex.split(command)[1:]
    p = subprocess.run(
        [sys.executable, "-c", BLOCK_PYARROW, *argv],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 1, (p.stdout, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "(pyarrow is not installed): pip install 'uasnav[fleet]'" in lines[0], p.stderr
    # training from flight logs alone imports the element table without pyarrow
    code = BLOCK_PYARROW.replace("from uasnav.cli import main; main()", "")
    code += "from uasnav.trajectory.element_table import training_samples, is_element_dataset"
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
