# Sourced by the scripts: puts cargo on PATH, gives Mesa a runtime folder so it does not
# print warnings about a missing XDG_RUNTIME_DIR on headless machines, and names the driver
# the ray-query tests run on.
if [ -f "$HOME/.cargo/env" ]; then
    # shellcheck disable=SC1091
    . "$HOME/.cargo/env"
fi
if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "${XDG_RUNTIME_DIR}" ]; then
    XDG_RUNTIME_DIR="$(mktemp -d)"
    chmod 700 "$XDG_RUNTIME_DIR"
    export XDG_RUNTIME_DIR
fi
# Mesa 25's lavapipe, unpacked by scripts/setup.sh: the driver with ray queries that
# tests/pathtrace/ray_query.rs runs on.
ray_query_icd="${XDG_CACHE_HOME:-$HOME/.cache}/lumagraph/lavapipe-ray-query/lvp_icd.json"
if [ -z "${LUMAGRAPH_RAY_QUERY_ICD:-}" ] && [ -f "$ray_query_icd" ]; then
    export LUMAGRAPH_RAY_QUERY_ICD="$ray_query_icd"
fi
# Open Image Denoise, unpacked by scripts/setup.sh: the library the OIDN node loads.
oidn_lib="${XDG_CACHE_HOME:-$HOME/.cache}/lumagraph/oidn/lib/libOpenImageDenoise.so.2"
if [ -z "${LUMAGRAPH_OIDN_LIB:-}" ] && [ -f "$oidn_lib" ]; then
    export LUMAGRAPH_OIDN_LIB="$oidn_lib"
fi
