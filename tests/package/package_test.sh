#!/usr/bin/env bash
# The installed package, as a studio would adopt it. One step per CTest entry (a fixture chain); the
# steps share a temporary folder outside the source and build trees, whose path STATE holds.
#   package_test.sh install STATE BUILD_DIR     cmake --install into an empty prefix; lists the files
#                                               and fails on anything but the library's own
#   package_test.sh host STATE EXAMPLE_DIR PNG_CHECK  configures and builds the raw-Vulkan host out of
#                                               tree against the prefix only, runs it from an unrelated
#                                               directory with no shader folder and checks its PNG
#   package_test.sh version STATE               find_package(shadows 1.0 CONFIG) succeeds,
#                                               find_package(shadows 99 CONFIG) fails cleanly
#   package_test.sh cleanup STATE               removes the temporary folder
set -euo pipefail
step=$1 state=$2
shift 2
fail() { echo "package_test: $*" >&2; exit 1; }
if [[ $step != install ]]; then
  [[ -f $state ]] || fail "no installed prefix (the install step did not run)"
  work=$(cat "$state")
  [[ $step == cleanup ]] || [[ -d $work/prefix ]] || fail "no installed prefix in $work"
fi

case $step in
install)
  build=$1
  [[ -f $state ]] && rm -rf "$(cat "$state")"
  work=$(mktemp -d "${TMPDIR:-/tmp}/shadows_package.XXXXXX")
  echo "$work" >"$state"
  prefix=$work/prefix
  cmake --install "$build" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; fail "cmake --install failed"; }
  echo "installed files:"
  (cd "$prefix" && find . \( -type f -o -type l \) | sed 's|^\./||' | sort) | tee "$work/installed.txt"
  unexpected=$(grep -Ev '^(include/shadows/[a-z_]+\.(hpp|glsl)|lib/libshadows\.(a|so(\.[0-9.]+)?)|lib/cmake/shadows/[A-Za-z_-]+\.cmake|lib/pkgconfig/shadows\.pc)$' \
               "$work/installed.txt" || true)
  [[ -z $unexpected ]] || fail "installed files outside the package: $unexpected"
  for f in include/shadows/shadows.hpp include/shadows/context.hpp include/shadows/settings.hpp include/shadows/version.hpp \
           lib/cmake/shadows/shadowsConfig.cmake lib/cmake/shadows/shadowsConfigVersion.cmake \
           lib/cmake/shadows/shadowsTargets.cmake lib/pkgconfig/shadows.pc; do
    [[ -f $prefix/$f ]] || fail "missing $f"
  done
  ls "$prefix"/lib/libshadows.* >/dev/null 2>&1 || fail "missing lib/libshadows"
  # The public headers name nothing but Vulkan, the standard library and each other.
  if grep -h '#include' "$prefix"/include/shadows/*.hpp | grep -Ev '<vulkan/vulkan\.h>|<[a-z_]+>|"shadows/[a-z_]+\.hpp"'; then
    fail "a public header includes something outside Vulkan, std and shadows/"
  fi
  # pkg-config resolves the installed file (Vulkan is its one requirement).
  PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --exists --print-errors "shadows >= 1.0" || fail "pkg-config cannot use shadows.pc"
  echo "pkg-config: $(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --cflags --libs shadows)"
  ;;
host)
  example=$(realpath "$1") png_check=$(realpath "$2")
  prefix=$work/prefix
  rm -rf "$work/host" "$work/run"
  cmake -S "$example" -B "$work/host" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$work/host_configure.log" 2>&1 ||
    { cat "$work/host_configure.log"; fail "configuring the host against the prefix failed"; }
  # Nothing of the source tree but the example's own folder may appear in its build.
  source_root=$(cd "$example/../.." && pwd)
  if grep -rhF "$source_root" "$work/host/CMakeCache.txt" "$work/host/CMakeFiles" --include='*.txt' --include='*.make' \
       --include='CMakeCache.txt' | grep -vF "$example"; then
    fail "the out-of-tree build refers to the project's tree outside the example's folder"
  fi
  cmake --build "$work/host" -j2 >"$work/host_build.log" 2>&1 || { tail -40 "$work/host_build.log"; fail "building the host failed"; }
  [[ ! -e $work/host/shaders ]] || fail "a shaders/ folder lies beside the host"
  mkdir -p "$work/run"
  cd "$work/run"
  env -u ENGINE_SHADER_DIR ENGINE_DEVICE=lavapipe "$work/host/vulkan_host" --device lavapipe --validation --size 160x90 \
    --frames 3 --mode izb+csm --out host.png
  "$png_check" host.png --min-size 160x90 --min-colors 8
  ;;
version)
  prefix=$work/prefix
  probe() {  # probe DIR VERSION: configures a project asking for shadows VERSION
    mkdir -p "$1"
    cat >"$1/CMakeLists.txt" <<CML
cmake_minimum_required(VERSION 3.25)
project(probe LANGUAGES CXX)
find_package(shadows $2 CONFIG)
if(NOT shadows_FOUND)
  message(FATAL_ERROR "shadows $2 not found")
endif()
if(NOT TARGET shadows::shadows)
  message(FATAL_ERROR "no shadows::shadows")
endif()
get_target_property(inc shadows::shadows INTERFACE_INCLUDE_DIRECTORIES)
message(STATUS "shadows \${shadows_VERSION}: \${inc}")
CML
    cmake -S "$1" -B "$1/build" -DCMAKE_PREFIX_PATH="$prefix" >"$1/log" 2>&1
  }
  rm -rf "$work/probe_1" "$work/probe_99"
  probe "$work/probe_1" 1.0 || { cat "$work/probe_1/log"; fail "find_package(shadows 1.0 CONFIG) failed"; }
  grep -- "-- shadows 1.0.0: $prefix/include" "$work/probe_1/log" || { cat "$work/probe_1/log"; fail "unexpected version or include path"; }
  if probe "$work/probe_99" 99; then fail "find_package(shadows 99 CONFIG) succeeded"; fi
  grep -q "shadows 99 not found" "$work/probe_99/log" || { cat "$work/probe_99/log"; fail "find_package(shadows 99) failed for another reason"; }
  grep -A3 "version" "$work/probe_99/log" | head -8
  ;;
cleanup)
  rm -rf "$work" "$state"
  ;;
*) fail "unknown step $step" ;;
esac
echo "package_test: $step ok"
