#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine (root, or a user with sudo):
#   tools/bootstrap.sh quickstart   install dependencies, build, run a small real evolution
#   tools/bootstrap.sh test         install dependencies, build, run the whole test suite
#   tools/bootstrap.sh sanitize     the test suite built with -fsanitize=address,undefined
#   tools/bootstrap.sh clang        the physics bit tests built with clang (same golden hashes)
#   tools/bootstrap.sh minimal      a cluster build without root (docs/cluster.md): softevo-mpi
#                                   built by an unprivileged user, Eigen and CLI11 found through
#                                   CMAKE_PREFIX_PATH (as cluster modules provide them),
#                                   nlohmann-json and toml++ downloaded, GoogleTest, libpng and
#                                   Python off
#   tools/bootstrap.sh aarch64      the same bits on AArch64: the core cross-compiled with Debian's
#                                   g++-aarch64-linux-gnu, its bit tests run under qemu-user
#   tools/bootstrap.sh fuzz [SECONDS]  the libFuzzer targets (robot file, config, archive reader)
#                                   built with clang and run for SECONDS each (default 30); any
#                                   crash, leak, timeout or out-of-memory fails; first the clang
#                                   bit tests (as `clang`) in the same build
# Idempotent: packages already installed are not touched, builds are incremental.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
JOBS=$(nproc)
PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev                      # physics: vector math
  libopenmpi-dev openmpi-bin         # softevo-mpi: master/worker ranks
  libhdf5-dev                        # run archives and traces
  libgtest-dev                       # tests
  libcli11-dev libtomlplusplus-dev nlohmann-json3-dev  # command lines, config, JSON
  libpng-dev                         # headless rendering to PNG
  libgif-dev                         # ... and to animated GIF
  libstb-dev fonts-dejavu-core       # render labels: stb_truetype and the DejaVu Sans font
  python3 python3-numpy python3-scipy python3-matplotlib  # analysis/ figures
  python3-h5py                       # the analysis test writes synthetic archives with it
  python3-dev pybind11-dev python3-pybind11  # the softevo Python package (python/, pybind11)
  python3-pytest python3-pandas      # its tests; run.individuals() as a pandas DataFrame
  libboost-dev zlib1g-dev            # softevo view: Boost.Beast (HTTP, WebSocket), zlib (--export-html)
  lib3mf-dev                         # softevo fabricate: 3MF writing and --check (lib3mf 1.x)
  python3-stl admesh                 # its tests: independent STL readers (numpy-stl, admesh)
)

# Open MPI refuses to run as root without these; harmless for other users.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# More ranks than cores (tests at np=3 on 2 cores) need oversubscription.
export OMPI_MCA_rmaps_base_oversubscribe=1

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

install_dependencies() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "== installing: ${missing[*]}"
    as_root apt-get update
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      -o DPkg::Lock::Timeout=600 "${missing[@]}"
  fi
}

REQUIRE_ALL=(-DSOFTEVO_REQUIRE_TESTS=ON -DSOFTEVO_REQUIRE_PNG=ON -DSOFTEVO_REQUIRE_GIF=ON -DSOFTEVO_REQUIRE_MPI=ON
  -DSOFTEVO_REQUIRE_HDF5=ON -DSOFTEVO_REQUIRE_VIEW=ON -DSOFTEVO_REQUIRE_3MF=ON)

# The page of `softevo view` (view/web): three.js (and, for the browser test, puppeteer-core)
# from the npm registry at the versions of view/web/package-lock.json. Node.js and npm come from
# Debian unless the machine has them already (a NodeSource nodejs includes npm, and Debian's npm
# package would conflict with it). npm ci runs again only when the lock file changed.
install_viewer_packages() {
  if ! command -v npm >/dev/null 2>&1; then
    as_root apt-get update
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      -o DPkg::Lock::Timeout=600 nodejs npm
  fi
  local web="$ROOT/view/web"
  if cmp -s "$web/package-lock.json" "$web/node_modules/.softevo-lock"; then return 0; fi
  echo "== npm ci in view/web (three.js for the page, puppeteer-core for its test)"
  (cd "$web" && npm ci --no-audit --no-fund)
  cp "$web/package-lock.json" "$web/node_modules/.softevo-lock"
}
# The Python package is built for Debian's /usr/bin/python3 (cmake/SoftevoDependencies.cmake).
PYTHON=/usr/bin/python3

# install_python_package: a .pth file in the user's site-packages of $PYTHON pointing at
# build/python, so that `python3 -c "import softevo"` works in a fresh shell (the package stays
# the build's: a rebuild updates it, nothing is copied).
install_python_package() {
  if [ ! -d "$ROOT/build/python/softevo" ]; then
    echo "== the softevo Python package was not built (pybind11-dev or python3-dev missing)"
    return 0
  fi
  local site
  site=$("$PYTHON" -c 'import site; print(site.getusersitepackages())')
  mkdir -p "$site"
  echo "$ROOT/build/python" >"$site/softevo-build.pth"
  (cd / && "$PYTHON" -c "import softevo") &&
    echo "== $PYTHON imports softevo from $ROOT/build/python (via $site/softevo-build.pth)"
}

# configure_timed DIR [cmake options...]: fresh configure, prints its time and what it builds.
configure_timed() {
  local dir=$1
  shift
  rm -rf "$dir"
  local t0=$SECONDS
  cmake -S "$ROOT" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSOFTEVO_WERROR=ON "$@" |
    sed -n '/softevo configuration:/,/builds /p'
  echo "== configured $(basename "$dir") in $((SECONDS - t0)) s"
}

# build_timed DIR TARGET...
build_timed() {
  local dir=$1
  shift
  local t0=$SECONDS
  cmake --build "$dir" -j"$JOBS" --target "$@"
  echo "== built $* in $((SECONDS - t0)) s"
}

# run_clang_bit_tests DIR: builds and runs the physics bit tests in a clang build tree.
run_clang_bit_tests() {
  local dir=$1
  build_timed "$dir" test_physics_determinism test_reproducible_math physics_golden_hash \
    test_elman_tanh
  "$dir/tests/test_physics_determinism"
  "$dir/tests/test_reproducible_math"
  "$dir/tests/test_elman_tanh"  # the controller's tanh: the same bits with clang
  # The wide physics objects export only their tables when clang optimises them too.
  ctest --test-dir "$dir" --output-on-failure -R '^PhysicsIsa\.'
}

# build DIR [cmake options...]
build() {
  local dir=$1
  shift
  cmake -S "$ROOT" -B "$dir" -G Ninja "$@" >/dev/null
  cmake --build "$dir" -j"$JOBS"
}

# The build/ tree of `quickstart` and `test`: one configuration (Release, -Werror, every
# optional part required), so that `test` after `quickstart` rebuilds nothing that the
# quickstart built; the quickstart builds only its targets, `test` the rest (tests included).
MAIN_BUILD_OPTIONS=(-DCMAKE_BUILD_TYPE=Release -DSOFTEVO_WERROR=ON "${REQUIRE_ALL[@]}"
  -DSOFTEVO_REQUIRE_PYTHON=ON)
# What the quickstart needs: the CLI (softevo evolve, info, render, view), softevo-mpi (the
# README's cluster path) and the Python package.
QUICKSTART_TARGETS=(softevo softevo-mpi softevo_python)

case "${1:-}" in
  quickstart)
    install_dependencies
    install_viewer_packages
    t0=$SECONDS
    cmake -S "$ROOT" -B "$ROOT/build" -G Ninja "${MAIN_BUILD_OPTIONS[@]}" >/dev/null
    cmake --build "$ROOT/build" -j"$JOBS" --target "${QUICKSTART_TARGETS[@]}"
    echo "== built ${QUICKSTART_TARGETS[*]} in $((SECONDS - t0)) s"
    install_python_package
    cd "$ROOT"
    mkdir -p runs
    # A new archive per call, so no earlier result is ever replaced. `softevo evolve`: the run
    # of softevo-mpi in one process, one worker thread per core (docs/mpi-local.md).
    run="runs/quickstart-$(date +%Y%m%d-%H%M%S).h5"
    t0=$SECONDS
    "$ROOT/build/bin/softevo" evolve --config configs/quickstart.toml --out "$run"
    echo "== evolved in $((SECONDS - t0)) s"
    "$ROOT/build/bin/softevo" info "$run" | sed '/^# resolved config/,$d'
    "$ROOT/build/bin/softevo" render "$run" --best --timelapse 4 --start 0.5 --span 2 \
      -o "${run%.h5}-best.png"
    echo "== next: build/bin/softevo replay $run --best --verify"
    ;;
  test)
    PACKAGES+=(chromium)  # the viewer's real-browser test (ctest label browser)
    PACKAGES+=(python3-nbclient python3-ipykernel)  # examples/quickstart.ipynb, run headless
    install_dependencies
    install_viewer_packages
    export SOFTEVO_REQUIRE_BROWSER_TEST=1  # chromium and npm ci are here: the test may not skip
    export SOFTEVO_REQUIRE_NOTEBOOK=1      # so are nbclient and ipykernel
    # Every optional part required: a missing package fails the configure, never skips tests.
    # The quickstart's configuration: what it built is not built again.
    build "$ROOT/build" "${MAIN_BUILD_OPTIONS[@]}"
    ctest --test-dir "$ROOT/build" --output-on-failure -j"$JOBS" -LE long
    ;;
  sanitize)
    PACKAGES+=(clang)
    install_dependencies
    # Without the Python package: an instrumented extension cannot be loaded by an
    # uninstrumented interpreter (the sanitizer runtime must come first).
    # -O1 -g1: half the compile time of RelWithDebInfo's -O2 -g (measured on cmd_eval.cpp:
    # 47 s against 92 s of CPU), and line tables are all a sanitizer report needs.
    # Built with clang: the instrumented tree compiles in about two thirds of GCC's CPU time
    # (docs/guide.md "Tests"), and a second compiler's sanitizers check the code GCC builds.
    build "$ROOT/build-sanitize" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
      -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTEVO_SANITIZE=ON \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
      -DSOFTEVO_WERROR=ON "${REQUIRE_ALL[@]}" -DCMAKE_DISABLE_FIND_PACKAGE_Python=ON
    # Open MPI's own allocations are reported as leaks; they are not ours. The launcher fault
    # tests (SoftevoMpiFaults) time signals against mpirun's one-second grace, which an
    # instrumented build does not keep: the test mode runs them. The viewer's browser test
    # measures the live simulation against real time, which an instrumented build cannot keep.
    # The MPI tests run at np=2 only: np=3 runs the same code with one more worker (both run in
    # the test mode), and instrumented it costs four minutes of the two cores.
    # The write-step fault tests take every other step per pass (tests/master/test_run.cpp).
    # RoughWalk and ChampionsFast check how far champions walk (seconds of simulated time, 170 s
    # of the instrumented suite's CPU); the same step code runs instrumented in the champion
    # determinism tests (EvalDeterminism, every SIMD width), so here they would add time only.
    ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 SOFTEVO_TEST_STEP_STRIDE=2 \
      ctest --test-dir "$ROOT/build-sanitize" --output-on-failure -j"$JOBS" -LE "long|no_sanitize|browser" \
      -E '^SoftevoMpiFaults\.|\.np3$|^RoughWalk\.|^ChampionsFast\.'
    ;;
  clang)
    # The physics gives the same bits with clang as with GCC: the golden hashes (every SIMD
    # width, both integrators), the lane/scalar bits of the reproducible math and the
    # controller's tanh. (CI runs these in the fuzz build, which compiles the physics with clang
    # anyway: see run_clang_bit_tests.)
    PACKAGES+=(clang)
    install_dependencies
    cmake -S "$ROOT" -B "$ROOT/build-clang" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DSOFTEVO_WERROR=ON -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >/dev/null
    run_clang_bit_tests "$ROOT/build-clang"
    ;;
  minimal)
    install_dependencies
    # A cluster: a compiler, CMake, MPI and HDF5 (C) from the system, libraries from module
    # prefixes on CMAKE_PREFIX_PATH, no root. The prefix is made here from Debian's Eigen and
    # CLI11 (their CMake package files are relocatable); nlohmann-json and toml++ come from their
    # pinned, hash-checked downloads (SOFTEVO_FETCH_MISSING); the optional parts are off.
    modules=/tmp/softevo-minimal-modules
    rm -rf "$modules"
    mkdir -p "$modules/include" "$modules/share/cmake" "$modules/share/eigen3"
    cp -r /usr/include/eigen3 /usr/include/CLI "$modules/include/"
    cp -r /usr/share/eigen3/cmake "$modules/share/eigen3/"
    cp -r /usr/share/cmake/CLI11 "$modules/share/cmake/"
    src=$ROOT
    builder=()
    if [ "$(id -u)" -eq 0 ]; then
      # As root, the build runs as an unprivileged user, on a copy of the tree if that user
      # cannot read this one (a clone under /root).
      id softevo-build >/dev/null 2>&1 || useradd --create-home softevo-build
      builder=(runuser -u softevo-build --)
      if ! "${builder[@]}" test -r "$ROOT/CMakeLists.txt"; then
        src=/tmp/softevo-minimal-src
        rm -rf "$src"
        mkdir -p "$src"
        tar -C "$ROOT" --exclude='./build*' --exclude=./.git -cf - . | tar -C "$src" -xf -
        chown -R softevo-build "$src"
      fi
    fi
    dir=/tmp/softevo-build-minimal-mpi
    rm -rf "$dir"
    mkdir -p "$dir"
    [ ${#builder[@]} -eq 0 ] || chown softevo-build "$dir"
    t0=$SECONDS
    # Unoptimised (-O0): this checks that the cluster configuration finds, compiles and links
    # everything; the code itself is compiled with -O3 -Werror by the test suite's build, and
    # -O0 takes about half the CPU time of those 520 s.
    "${builder[@]}" cmake -S "$src" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Debug \
      -DCMAKE_CXX_FLAGS_DEBUG=-O0 -DCMAKE_C_FLAGS_DEBUG=-O0 \
      -DSOFTEVO_WERROR=ON -DCMAKE_PREFIX_PATH="$modules" \
      -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON -DCMAKE_DISABLE_FIND_PACKAGE_PNG=ON \
      -DCMAKE_DISABLE_FIND_PACKAGE_GIF=ON \
      -DCMAKE_DISABLE_FIND_PACKAGE_Python=ON \
      -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON -DCMAKE_DISABLE_FIND_PACKAGE_tomlplusplus=ON \
      -DSOFTEVO_REQUIRE_MPI=ON -DSOFTEVO_REQUIRE_HDF5=ON | sed -n '/softevo configuration:/,/builds /p'
    echo "== configured the minimal build as $("${builder[@]}" id -un) in $((SECONDS - t0)) s"
    for package in Eigen3 CLI11; do
      found=$(sed -n "s/^${package}_DIR:PATH=//p" "$dir/CMakeCache.txt")
      case "$found" in
        "$modules"/*) echo "== $package from CMAKE_PREFIX_PATH: $found" ;;
        *) echo "minimal: $package was not found through CMAKE_PREFIX_PATH ($found)" >&2; exit 1 ;;
      esac
    done
    t0=$SECONDS
    "${builder[@]}" cmake --build "$dir" -j"$JOBS" --target softevo-mpi
    echo "== built softevo-mpi in $((SECONDS - t0)) s"
    "${builder[@]}" "$dir/bin/softevo-mpi" --version
    # The core without MPI and HDF5 is built (and its bit tests run) by the aarch64 mode, whose
    # cross toolchain has neither.
    ;;
  aarch64)
    # The core (common, physics, evo, worker) cross-compiled for AArch64 (toolchain:
    # cmake/aarch64-linux-gnu.cmake) and its bit tests run under user-mode qemu: the golden
    # hashes at the scalar and NEON widths, the reproducible math, the floor, the C library's
    # functions of the evaluation and short champion evaluations, all against the x86-64 bits.
    PACKAGES+=(g++-aarch64-linux-gnu libc6-arm64-cross qemu-user-static)
    install_dependencies
    toolchain="$ROOT/cmake/aarch64-linux-gnu.cmake"
    gtest="$ROOT/build-aarch64-gtest"
    if [ ! -f "$gtest/install/lib/cmake/GTest/GTestConfig.cmake" ]; then
      # GoogleTest for AArch64, from the sources libgtest-dev ships
      t0=$SECONDS
      cmake -S /usr/src/googletest -B "$gtest/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_TOOLCHAIN_FILE="$toolchain" -DBUILD_GMOCK=OFF \
        -DCMAKE_INSTALL_PREFIX="$gtest/install" >/dev/null
      cmake --build "$gtest/build" -j"$JOBS" >/dev/null
      cmake --install "$gtest/build" >/dev/null
      echo "== built GoogleTest for AArch64 in $((SECONDS - t0)) s"
    fi
    configure_timed "$ROOT/build-aarch64" -DCMAKE_TOOLCHAIN_FILE="$toolchain" \
      -DGTest_DIR="$gtest/install/lib/cmake/GTest" -DSOFTEVO_REQUIRE_TESTS=ON
    build_timed "$ROOT/build-aarch64" physics_golden_hash test_physics_determinism \
      test_reproducible_math test_floor test_libm_bits test_elman_tanh test_champion_bits
    # No fused multiply-add anywhere in the physics (it would round differently from x86-64):
    # -ffp-contract=off must keep GCC from fusing the NEON lanes' products and sums.
    fused=$(aarch64-linux-gnu-objdump -d "$ROOT"/build-aarch64/physics/CMakeFiles/physics.dir/*.o |
      grep -cE '[[:space:]](fmla|fmls|fmadd|fmsub|fnmadd|fnmsub|fnmla|fnmls)[[:space:]]' || true)
    echo "== fused multiply-add instructions in the AArch64 physics objects: $fused"
    [ "$fused" -eq 0 ]
    # run_aarch64 LOG EXE [ARGS...]: EXE under qemu, its output to LOG; returns its exit code.
    run_aarch64() {
      local log=$1 t0=$SECONDS rc=0
      shift
      (cd "$ROOT" && SOFTEVO_SOURCE_DIR="$ROOT" qemu-aarch64-static -L /usr/aarch64-linux-gnu "$@") \
        >"$log" 2>&1 || rc=$?
      echo "== $(basename "$1") ${2:-} under qemu-aarch64: $((SECONDS - t0)) s, exit $rc" >>"$log"
      return $rc
    }
    tests="$ROOT/build-aarch64/tests"
    logs="$ROOT/build-aarch64/qemu-logs"
    mkdir -p "$logs"
    # Two streams of about equal length, one per core (qemu runs one thread per test).
    (run_aarch64 "$logs/1" "$tests/test_physics_determinism" &&
      run_aarch64 "$logs/2" "$tests/test_reproducible_math" &&
      run_aarch64 "$logs/3" "$tests/test_floor") &
    first=$!
    (run_aarch64 "$logs/4" "$tests/test_champion_bits" &&
      run_aarch64 "$logs/5" "$tests/test_libm_bits" &&
      run_aarch64 "$logs/6" "$tests/test_elman_tanh") &
    second=$!
    rc=0
    wait $first || rc=1
    wait $second || rc=1
    for log in "$logs"/[1-6]; do grep -vE '^\[ RUN|^$' "$log" || true; done
    [ $rc -eq 0 ]
    ;;
  fuzz)
    # libFuzzer ships in libclang-rt-14-dev (libclang_rt.fuzzer-x86_64.a), which clang only
    # recommends: --no-install-recommends would leave it out.
    PACKAGES+=(clang libclang-rt-14-dev)
    install_dependencies
    seconds=${2:-30}
    dir="$ROOT/build-fuzz"
    cmake -S "$ROOT" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTEVO_WERROR=ON \
      -DSOFTEVO_ENABLE_FUZZ=ON -DSOFTEVO_REQUIRE_HDF5=ON -DCMAKE_C_COMPILER=clang \
      -DCMAKE_CXX_COMPILER=clang++ >/dev/null
    build_timed "$dir" fuzz_robot_file fuzz_config fuzz_archive fuzz_seeds
    # This tree compiles the physics with clang (-O2, uninstrumented: the fuzz instrumentation
    # is on the readers only), so the clang bit tests (the `clang` mode) run here too, at the
    # cost of their three test programs.
    run_clang_bit_tests "$dir"
    # fuzz_one TARGET: one fuzzer for the budget; its summary line, and on a failure the report.
    fuzz_one() {
      local target=$1 t0=$SECONDS rc=0
      # The corpus grows in the build tree (seeds from fuzz/make_seeds.cpp); a crashing input
      # is saved there as crash-* and printed.
      local corpus="$dir/fuzz/corpus/$target"
      mkdir -p "$corpus" "$dir/fuzz/artifacts"
      # An archive is one HDF5 file of ~30 kB: inputs up to 64 kB. Leaks are not checked there:
      # libhdf5 itself leaks on some of its error paths (an empty file leaks 37 kB in H5Fopen),
      # and libFuzzer's own -detect_leaks would run every such input twice. libhdf5 allocates
      # heavily, so a smaller quarantine (recent frees are still checked) and no malloc fill
      # keep the sanitizer from dominating: 2x the inputs per second.
      local extra=() asan=allocator_may_return_null=1:detect_leaks=1
      # A config reaches 64 kB too: beyond its stated line limit (common/config.hpp), where the
      # default cap of 4 kB hid a stack overflow on a 50 kB line (issue 39).
      [ "$target" = config ] && extra=(-max_len=65536)
      if [ "$target" = archive ]; then
        extra=(-max_len=65536 -detect_leaks=0)
        asan=allocator_may_return_null=1:detect_leaks=0:quarantine_size_mb=16:max_malloc_fill_size=0
      fi
      ASAN_OPTIONS=$asan "$dir/bin/fuzz_$target" \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$dir/fuzz/artifacts/$target-" "${extra[@]}" \
        "$corpus" "$dir/fuzz/seeds/$target" >"$dir/fuzz/$target.log" 2>&1 || rc=1
      local runs speed
      runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$dir/fuzz/$target.log" | tail -1)
      speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$dir/fuzz/$target.log" | tail -1)
      echo "== fuzz_$target: ${runs:-?} inputs in $((SECONDS - t0)) s (${speed:-?}/s)" \
        >"$dir/fuzz/$target.summary"
      return $rc
    }
    # The three run at once: each fuzzer is one process, so one after the other would leave a
    # core idle for the whole budget (each still gets its full time, at two thirds of a core).
    targets=(robot_file config archive)
    pids=()
    for target in "${targets[@]}"; do
      fuzz_one "$target" &
      pids+=($!)
    done
    rc=0
    for i in "${!targets[@]}"; do
      target=${targets[$i]}
      if ! wait "${pids[$i]}"; then
        rc=1
        # The report's head (the error and its stack), then libFuzzer's summary and artifact.
        grep -m1 -A40 -E '^==[0-9]+== ?ERROR|runtime error:' "$dir/fuzz/$target.log" || true
        tail -12 "$dir/fuzz/$target.log"
      fi
      cat "$dir/fuzz/$target.summary"
    done
    [ $rc -eq 0 ]
    ;;
  *)
    echo "usage: $0 quickstart|test|sanitize|clang|minimal|aarch64|fuzz [SECONDS]" >&2
    exit 2
    ;;
esac
