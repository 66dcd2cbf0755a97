#!/usr/bin/env bash
# Fetches MuJoCo 3.17.0 from the official `mujoco` wheel on PyPI and lays it out for mujoco-rs:
#   .mujoco/lib/libmujoco.so.3.17.0, .mujoco/lib/libmujoco.so -> libmujoco.so.3.17.0,
#   .mujoco/include/mujoco/*.h
# Idempotent: does nothing when the library is already there. Needs python3 with pip.
set -euo pipefail
VERSION=3.17.0
root="$(cd "$(dirname "$0")/.." && pwd)"
dest="$root/.mujoco"
lib="$dest/lib/libmujoco.so.$VERSION"
if [ -f "$lib" ] && [ -L "$dest/lib/libmujoco.so" ]; then
  exit 0
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
echo "modellint: fetching mujoco==$VERSION wheel from PyPI" >&2
# Pin the wheel's platform and Python tag so the same file is chosen whatever python3 is here;
# only the shared library and headers are used, never the Python module.
python3 -m pip download --quiet --no-deps --only-binary=:all: \
  --platform manylinux_2_28_x86_64 --python-version 3.11 --implementation cp \
  "mujoco==$VERSION" -d "$tmp"
whl="$(ls "$tmp"/mujoco-"$VERSION"-*.whl | head -n 1)"
python3 - "$whl" "$dest" "$VERSION" <<'PY'
import os, sys, zipfile
whl, dest, version = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(os.path.join(dest, "lib"), exist_ok=True)
os.makedirs(os.path.join(dest, "include", "mujoco"), exist_ok=True)
with zipfile.ZipFile(whl) as z:
    for name in z.namelist():
        if name == f"mujoco/libmujoco.so.{version}":
            out = os.path.join(dest, "lib", os.path.basename(name))
        elif name.startswith("mujoco/include/mujoco/") and name.endswith(".h"):
            out = os.path.join(dest, "include", "mujoco", os.path.basename(name))
        else:
            continue
        with z.open(name) as src, open(out + ".part", "wb") as dst:
            dst.write(src.read())
        os.replace(out + ".part", out)
PY
ln -sf "libmujoco.so.$VERSION" "$dest/lib/libmujoco.so"
test -f "$lib" || { echo "modellint: libmujoco.so.$VERSION not found in the wheel" >&2; exit 1; }
echo "modellint: MuJoCo $VERSION ready in $dest/lib" >&2
