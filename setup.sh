#!/usr/bin/env bash
# Sets the project up on a fresh Debian 12 machine: installs the Debian packages it needs (only those
# missing; quiet when all are present), then configures and builds into build/.
# Options: BUILD_DIR (default build), BUILD_TYPE (default Release); CI=true turns warnings into errors.
set -euo pipefail
cd "$(dirname "$0")"

packages=(
  build-essential cmake pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools glslang-tools
  libglm-dev libglfw3-dev libimgui-dev libtinygltf-dev libgtest-dev libstb-dev nlohmann-json3-dev
  libembree-dev xvfb xauth python3
  clang libclang-rt-dev
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  [[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq >/dev/null
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

build_dir=${BUILD_DIR:-build}
werror=OFF
[[ "${CI:-}" == "true" ]] && werror=ON
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" -DENGINE_WARNINGS_AS_ERRORS=$werror >/dev/null
log="$build_dir/build.log"
if ! cmake --build "$build_dir" -j"$(nproc)" >"$log" 2>&1; then
  grep -E 'error|Error' -A3 "$log" | head -60
  echo "setup: build failed; full log in $log" >&2
  exit 1
fi
grep -E 'warning' "$log" | head -20 || true
echo "setup: built into $build_dir/bin"
