"""PEP 517 build backend for the modellint wheel: maturin, after laying out MuJoCo for the link.

mujoco-rs links against `libmujoco.so` in `.mujoco/lib` (`.cargo/config.toml`). `mujoco==3.17.0`
is a build requirement (pyproject.toml), so the library is already installed in the build
environment; copying it from there means `pip install .` needs no step before it and no second
download. `scripts/setup-mujoco.sh` (used by `make`) lays out the same files from the same wheel.

The installed binary does not use this copy: it finds `libmujoco.so.3.17.0` inside the installed
`mujoco` package through an rpath relative to itself (build.rs, feature `wheel`).
"""

import importlib.util
import os
import shutil
from pathlib import Path

import maturin
from maturin import (  # noqa: F401  (re-exported PEP 517 hooks)
    build_sdist,
    get_requires_for_build_sdist,
    get_requires_for_build_wheel,
    prepare_metadata_for_build_wheel,
)

VERSION = "3.17.0"
ROOT = Path(__file__).resolve().parent.parent


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


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    _lay_out_mujoco()
    return maturin.build_wheel(wheel_directory, config_settings, metadata_directory)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    _lay_out_mujoco()
    return maturin.build_editable(wheel_directory, config_settings, metadata_directory)
