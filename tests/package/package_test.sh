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
# Two steps stand alone (a temporary folder of their own, removed at exit; STATE is unused):
#   package_test.sh module_only - SOURCE_ROOT PNG_CHECK
#                       configures modules/shadows by itself with the engine's other dependencies
#                       hidden from CMake and pkg-config, builds and installs it, checks that it
#                       compiled nothing outside modules/shadows, engine/gpu and its build folder, then
#                       builds the raw-Vulkan host against that prefix and runs it
#   package_test.sh add_subdirectory - SOURCE_ROOT PNG_CHECK
#                       builds the host with the module's sources added by add_subdirectory, the
#                       same dependencies hidden, and runs it
set -euo pipefail
step=$1 state=$2
shift 2
fail() { echo "package_test: $*" >&2; exit 1; }

# Runs the host built in $1 from an unrelated directory with no shader folder and checks its PNG ($2).
run_host() {
  local host_build=$1 png_check=$2 run_dir=$1/../run
  [[ ! -e $host_build/shaders ]] || fail "a shaders/ folder lies beside the host"
  mkdir -p "$run_dir"
  (cd "$run_dir" &&
    env -u ENGINE_SHADER_DIR ENGINE_DEVICE=lavapipe "$host_build/vulkan_host" --device lavapipe --validation --size 160x90 \
      --frames 3 --mode izb+csm --out host.png &&
    "$png_check" host.png --min-size 160x90 --min-colors 8) || fail "the host did not run cleanly"
}

# What a build of the module alone may see: of pkg-config's files, only those named (Vulkan's, and
# stb's for the host's PNG output); of CMake packages, none of the engine's, tests' or window's.
hide_engine_dependencies() {  # hide_engine_dependencies DIR PC_NAME...
  local dir=$1
  shift
  mkdir -p "$dir"
  for pc in "$@"; do ln -sf "$(pkg-config --variable=pcfiledir "$pc")/$pc.pc" "$dir/$pc.pc"; done
  export PKG_CONFIG_LIBDIR=$dir PKG_CONFIG_PATH=
  hidden_packages=()
  for pkg in TinyGLTF nlohmann_json embree GTest glfw3 imgui; do hidden_packages+=("-DCMAKE_DISABLE_FIND_PACKAGE_$pkg=ON"); done
}

case $step in
module_only | add_subdirectory)
  root=$(realpath "$1") png_check=$(realpath "$2")
  work=$(mktemp -d "${TMPDIR:-/tmp}/shadows_alone.XXXXXX")
  trap 'rm -rf "$work"' EXIT
  example=$root/sample_game/vulkan_host
  if [[ $step == module_only ]]; then
    (
      hide_engine_dependencies "$work/pc" vulkan
      cmake -S "$root/modules/shadows" -B "$work/module" -DCMAKE_BUILD_TYPE=Release -DSHADOWS_WARNINGS_AS_ERRORS=ON \
        -DCMAKE_EXPORT_COMPILE_COMMANDS=ON "${hidden_packages[@]}" >"$work/configure.log" 2>&1 ||
        { cat "$work/configure.log"; fail "configuring modules/shadows on its own failed"; }
      cmake --build "$work/module" -j2 >"$work/build.log" 2>&1 || { tail -40 "$work/build.log"; fail "building modules/shadows on its own failed"; }
      cmake --install "$work/module" --prefix "$work/prefix" >"$work/install.log" || fail "installing modules/shadows failed"
    ) || exit 1
    # Every compiled file is the module's, the helper layer's or generated in the build folder.
    outside=$(grep -o '"file": *"[^"]*"' "$work/module/compile_commands.json" | sed 's/.*"\([^"]*\)"$/\1/' |
              grep -vE "^($root/modules/shadows/src/|$root/engine/gpu/|$work/module/)" || true)
    [[ -z $outside ]] || fail "the module's build compiled files outside modules/shadows and engine/gpu: $outside"
    echo "compiled: $(grep -c '"file"' "$work/module/compile_commands.json") files; installed: $(cd "$work/prefix" && find . -type f | wc -l) files"
    cmake -S "$example" -B "$work/host" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release >"$work/host_configure.log" 2>&1 ||
      { cat "$work/host_configure.log"; fail "configuring the host against the module's prefix failed"; }
  else
    (
      hide_engine_dependencies "$work/pc" vulkan stb
      cmake -S "$example" -B "$work/host" -DCMAKE_BUILD_TYPE=Release -DVULKAN_HOST_SHADOWS_SOURCE_DIR="$root/modules/shadows" \
        "${hidden_packages[@]}" >"$work/host_configure.log" 2>&1
    ) || { cat "$work/host_configure.log"; fail "configuring the host with add_subdirectory(modules/shadows) failed"; }
  fi
  cmake --build "$work/host" -j2 >"$work/host_build.log" 2>&1 || { tail -40 "$work/host_build.log"; fail "building the host failed"; }
  run_host "$work/host" "$png_check"
  echo "package_test: $step ok"
  exit 0
  ;;
esac

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
  run_host "$work/host" "$png_check"
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
