"""PEP 517 build backend for the modellint wheel: maturin, after laying out MuJoCo for the link
and building the `modellint` binary.

mujoco-rs links against `libmujoco.so` in `.mujoco/lib` (`.cargo/config.toml`). `mujoco==3.17.0`
is a build requirement (pyproject.toml), so the library is already installed in the build
environment; copying it from there means `pip install .` needs no step before it and no second
download. `scripts/setup-mujoco.sh` (used by `make`) lays out the same files from the same wheel.

The installed binary does not use this copy: it finds `libmujoco.so.3.17.0` inside the installed
`mujoco` package through an rpath relative to itself (build.rs); so does the extension module
(python/native/build.rs).

maturin builds the extension module `modellint._native` (pyproject.toml); the `modellint` command
is the Rust binary, built here with `cargo build --release --locked --bin modellint` (the same
build as `make build`, so after it nothing recompiles) and put in the wheel's data scripts
(`tool.maturin.data`), which pip installs on PATH.
"""

import importlib.util
import json
import os
import shutil
import subprocess
from pathlib import Path

import maturin
from maturin import (  # noqa: F401  (re-exported PEP 517 hooks)
    get_requires_for_build_sdist,
    get_requires_for_build_wheel,
)

VERSION = "3.17.0"
ROOT = Path(__file__).resolve().parent.parent
# `tool.maturin.data` in pyproject.toml: maturin wants it to exist for every hook.
DATA = ROOT / "target" / "wheel-data"


def _lay_out_mujoco() -> None:
    lib_dir = ROOT / ".mujoco" / "lib"
    lib = lib_dir / f"libmujoco.so.{VERSION}"
    link = lib_dir / "libmujoco.so"
    if lib.is_file() and link.exists():
        return
    spec = importlib.util.find_spec("mujoco")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError(
            f"modellint: the build needs mujoco=={VERSION} (a build requirement in pyproject.toml)"
        )
    pkg = Path(list(spec.submodule_search_locations)[0])
    src = pkg / f"libmujoco.so.{VERSION}"
    if not src.is_file():
        raise RuntimeError(f"modellint: {src} not found: mujoco=={VERSION} is required")
    lib_dir.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src, str(lib) + ".part")
    os.replace(str(lib) + ".part", lib)
    if link.is_symlink() or link.exists():
        link.unlink()
    link.symlink_to(lib.name)
    headers = pkg / "include" / "mujoco"
    if headers.is_dir():
        dest = ROOT / ".mujoco" / "include" / "mujoco"
        dest.mkdir(parents=True, exist_ok=True)
        for h in headers.glob("*.h"):
            shutil.copyfile(h, dest / h.name)


def _build_binary() -> None:
    """`cargo build --release --locked --bin modellint`, copied (stripped) to the data scripts."""
    cargo = os.environ.get("CARGO", "cargo")
    subprocess.run(
        [cargo, "build", "--release", "--locked", "--bin", "modellint"], cwd=ROOT, check=True
    )
    meta = subprocess.run(
        [cargo, "metadata", "--format-version", "1", "--no-deps", "--locked"],
        cwd=ROOT,
        check=True,
        stdout=subprocess.PIPE,
    )
    binary = Path(json.loads(meta.stdout)["target_directory"]) / "release" / "modellint"
    scripts = DATA / "scripts"
    scripts.mkdir(parents=True, exist_ok=True)
    dest = scripts / "modellint"
    shutil.copyfile(binary, str(dest) + ".part")
    os.chmod(str(dest) + ".part", 0o755)
    strip = shutil.which("strip")
    if strip:
        subprocess.run([strip, "--strip-all", str(dest) + ".part"], check=True)
    os.replace(str(dest) + ".part", dest)


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    DATA.mkdir(parents=True, exist_ok=True)
    return maturin.prepare_metadata_for_build_wheel(metadata_directory, config_settings)


def build_sdist(sdist_directory, config_settings=None):
    DATA.mkdir(parents=True, exist_ok=True)
    return maturin.build_sdist(sdist_directory, config_settings)


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    _lay_out_mujoco()
    _build_binary()
    return maturin.build_wheel(wheel_directory, config_settings, metadata_directory)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    _lay_out_mujoco()
    _build_binary()
    return maturin.build_editable(wheel_directory, config_settings, metadata_directory)
