#!/usr/bin/env bash
# Installs what lumagraph needs on a Debian/Ubuntu machine, skipping what is already there:
# the Vulkan loader and Mesa's drivers (lavapipe, the CPU Vulkan driver, is the GPU of last
# resort and the one the tests run on), a C toolchain, Python 3 with its headers and venv
# (scripts/test.sh makes a test mesh with it; the Python package links it and is tested in a
# virtual environment), Embree 3 (the path tracer traces its rays with it on CPU adapters; loaded at
# run time, optional), Rust through rustup, and Intel Open Image Denoise 2 (the OIDN node's
# library, from the pyoidn wheel on PyPI; loaded at run time, optional), and Blender 4.2's
# colour config (from the bpy wheel on PyPI; optional).
# Safe to run again: it only installs what is missing.
set -euo pipefail

packages=(mesa-vulkan-drivers libvulkan1 ca-certificates curl gcc libc6-dev pkg-config python3 python3-dev python3-venv libembree3-3)
missing=()
for p in "${packages[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
    if [ -x "$HOME/.cargo/bin/cargo" ]; then
        :
    else
        echo "setup: installing Rust with rustup"
        curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal -c rustfmt,clippy
    fi
fi

# Mesa 25's lavapipe, beside the system's Vulkan drivers (not instead of them): it has ray
# queries, which the path tracer uses where a device offers them and whose tests need them
# (tests/pathtrace/ray_query.rs runs them on it). Debian bookworm's own Mesa (22.3) has none, and
# compiles shaders 2-3x faster, which the rest of the tests depend on. On bookworm, the
# bookworm-backports suite is added to apt's sources and the driver unpacked from its
# mesa-vulkan-drivers package into $ray_query_dir; scripts/env.sh points
# LUMAGRAPH_RAY_QUERY_ICD at it. Elsewhere: set LUMAGRAPH_RAY_QUERY_ICD to the ICD file of a
# Mesa 25 or later lavapipe, or LUMAGRAPH_ALLOW_NO_RAY_QUERY=1 to skip those tests.
ray_query_dir="${XDG_CACHE_HOME:-$HOME/.cache}/lumagraph/lavapipe-ray-query"
if [ ! -f "$ray_query_dir/lvp_icd.json" ] && grep -q '^VERSION_CODENAME=bookworm' /etc/os-release 2>/dev/null; then
    if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/; then
        echo "setup: adding Debian's bookworm-backports suite to apt's sources, for Mesa 25's lavapipe"
        printf '%s\n' 'Types: deb' 'URIs: http://deb.debian.org/debian' 'Suites: bookworm-backports' \
            'Components: main' 'Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg' |
            $sudo tee /etc/apt/sources.list.d/bookworm-backports.sources >/dev/null
        $sudo apt-get update -qq
    fi
    echo "setup: unpacking Mesa 25's lavapipe (ray queries) from bookworm-backports into $ray_query_dir"
    work=$(mktemp -d)
    chmod 777 "$work"
    if (cd "$work" && apt-get download -qq -t bookworm-backports mesa-vulkan-drivers 2>/dev/null) &&
        dpkg-deb -x "$work"/mesa-vulkan-drivers_*.deb "$work/root"; then
        mkdir -p "$ray_query_dir"
        lib=$(find "$work/root" -name libvulkan_lvp.so | head -n 1)
        cp "$lib" "$ray_query_dir/libvulkan_lvp.so"
        icd=$(find "$work/root" -name 'lvp_icd*.json' | head -n 1)
        api=$(sed -n 's/.*"api_version": *"\([^"]*\)".*/\1/p' "$icd" | head -n 1)
        printf '{\n  "file_format_version": "1.0.0",\n  "ICD": {\n    "library_path": "%s",\n    "api_version": "%s"\n  }\n}\n' \
            "$ray_query_dir/libvulkan_lvp.so" "$api" >"$ray_query_dir/lvp_icd.json.tmp"
        mv "$ray_query_dir/lvp_icd.json.tmp" "$ray_query_dir/lvp_icd.json"
    else
        echo "setup: could not fetch Mesa 25's lavapipe from bookworm-backports: the ray-query tests will fail (LUMAGRAPH_ALLOW_NO_RAY_QUERY=1 skips them)" >&2
    fi
    rm -rf "$work"
fi

# Sets `pip` to a pip command: the system Python's, or, where it has none (Debian's
# python3-pip is not installed), the one a virtual environment in $1 brings (python3-venv).
find_pip() {
    pip=(python3 -m pip)
    if ! python3 -m pip --version >/dev/null 2>&1; then
        python3 -m venv "$1/venv" >/dev/null 2>&1 && pip=("$1/venv/bin/python" -m pip)
    fi
}

# Open Image Denoise 2 (Intel), which the OIDN denoiser node loads at run time (optional:
# without it that node fails and says how to get it). The pyoidn wheel on PyPI ships the
# library; its CPU parts (libOpenImageDenoise, its core with the trained weights, the CPU
# device and TBB) are unpacked into $oidn_dir/lib, where the library's RPATH ($ORIGIN/../lib)
# finds them. scripts/env.sh points LUMAGRAPH_OIDN_LIB at it.
oidn_version=2.5.1
oidn_dir="${XDG_CACHE_HOME:-$HOME/.cache}/lumagraph/oidn"
if [ ! -f "$oidn_dir/lib/libOpenImageDenoise.so.2" ]; then
    echo "setup: fetching Open Image Denoise $oidn_version (the pyoidn wheel from PyPI) into $oidn_dir"
    work=$(mktemp -d)
    find_pip "$work"
    if "${pip[@]}" download -q --disable-pip-version-check --no-deps --only-binary=:all: \
        -d "$work" "pyoidn==$oidn_version" >/dev/null 2>&1 &&
        python3 - "$work"/pyoidn-*.whl "$work/lib" "$oidn_version" <<'PY'
import os, sys, zipfile
wheel, dest, version = sys.argv[1:4]
wanted = {"libOpenImageDenoise.so.2", f"libOpenImageDenoise_core.so.{version}",
          f"libOpenImageDenoise_device_cpu.so.{version}", "libtbb.so.12"}
os.makedirs(dest)
with zipfile.ZipFile(wheel) as z:
    for info in z.infolist():
        name = os.path.basename(info.filename)
        if info.filename.startswith("pyoidn/oidn/lib/") and name in wanted:
            with open(os.path.join(dest, name), "wb") as f:
                f.write(z.read(info))
            os.chmod(os.path.join(dest, name), 0o755)
            wanted.discard(name)
        elif info.filename.endswith("/licenses/LICENSE"):
            with open(os.path.join(dest, "LICENSE.pyoidn"), "wb") as f:
                f.write(z.read(info))
sys.exit(f"not in the wheel: {sorted(wanted)}" if wanted else 0)
PY
    then
        mkdir -p "$oidn_dir"
        rm -rf "$oidn_dir/lib"
        mv "$work/lib" "$oidn_dir/lib"
    else
        echo "setup: could not fetch Open Image Denoise (pip download pyoidn==$oidn_version): the OIDN node will not run; set LUMAGRAPH_OIDN_LIB to a libOpenImageDenoise.so (2.x) instead" >&2
    fi
    rm -rf "$work"
fi

# Blender 4.2's OpenColorIO config (AgX, Filmic, Khronos PBR Neutral: the views Blender
# users see), for the `blender` config of the colour nodes (optional: without it they say
# how to get it; LUMAGRAPH_BLENDER_OCIO may name a Blender install's config instead). Blender
# ships it inside its bpy wheel on PyPI (519 MB); its datafiles/colormanagement folder
# (24 MB: config.ocio and its LUTs) is unpacked into $blender_dir.
blender_version=4.2.0
blender_dir="${XDG_CACHE_HOME:-$HOME/.cache}/lumagraph/blender-ocio/4.2"
if [ ! -f "$blender_dir/config.ocio" ]; then
    echo "setup: fetching Blender $blender_version's colour config (from the bpy wheel on PyPI) into $blender_dir"
    work=$(mktemp -d)
    find_pip "$work"
    if "${pip[@]}" download -q --disable-pip-version-check --no-deps --only-binary=:all: \
        --python-version 3.11 -d "$work" "bpy==$blender_version" >/dev/null 2>&1 &&
        python3 - "$work"/bpy-*.whl "$work/colormanagement" <<'PY'
import os, sys, zipfile
wheel, dest = sys.argv[1:3]
prefix = "bpy/4.2/datafiles/colormanagement/"
with zipfile.ZipFile(wheel) as z:
    names = [n for n in z.namelist() if n.startswith(prefix) and not n.endswith("/")]
    for name in names:
        out = os.path.join(dest, name[len(prefix):])
        os.makedirs(os.path.dirname(out), exist_ok=True)
        with open(out, "wb") as f:
            f.write(z.read(name))
sys.exit(0 if os.path.isfile(os.path.join(dest, "config.ocio")) else "no config.ocio in the wheel")
PY
    then
        mkdir -p "$(dirname "$blender_dir")"
        rm -rf "$blender_dir"
        mv "$work/colormanagement" "$blender_dir"
    else
        echo "setup: could not fetch Blender's colour config (pip download bpy==$blender_version): the \`blender\` config will not load; set LUMAGRAPH_BLENDER_OCIO to a Blender install's datafiles/colormanagement/config.ocio instead" >&2
    fi
    rm -rf "$work"
fi
