#!/usr/bin/env bash
# Builds the tests with a sanitizer in a build directory of their own and runs them; any report
# fails the run (exit non-zero). CI runs both modes after the suite (tools/test.sh --sanitize).
# Compiler: clang 14 from Debian, as the fuzzer (tools/fuzz.sh). It compiles limber's
# Eigen-heavy files 2.4–3.3× faster than g++ 12 under ASan (kernel/world/world.cpp: 42 s
# against 132 s), which is what lets CI afford the sanitizers; g++ 12 also reports hundreds of
# false -Wuninitialized warnings inside its AVX-512 intrinsics once -fsanitize is on. A second
# compiler's warnings over the whole code are a gain of their own.
#
#   tools/sanitize.sh [address|thread] [ctest or test-program arguments...]
#
#   address (the default)  AddressSanitizer + UndefinedBehaviorSanitizer + LeakSanitizer over the
#                          whole suite, in build-asan/ (ctest -j2; extra arguments go to ctest,
#                          e.g. `tools/sanitize.sh address -LE stress` for the shortened form).
#   thread                 ThreadSanitizer, in build-tsan/: builds the test programs that start
#                          threads and runs the tests in them that do (the block runner's
#                          workers, parallel_for and task systems; the coloured relaxation; the
#                          threaded Verlet steps; the narrowphase on threads; the World on an
#                          engine's task system; the CLI's --threads; Featherstone's islands
#                          and contact groups). Extra arguments go to
#                          every program (a --gtest_filter=... replaces the list below).
#
# Both build -O2 -gline-tables-only with NDEBUG (the release build's code paths; at -O1 xsimd's
# batch operators stay calls and the SIMD tests run ~15× slower; line tables are all a report's
# stack needs — full -g made each file 25-30 % slower to compile, measured on
# kernel/model/model.cpp under both sanitizers) and
# -march=native as tools/setup.sh does (LIMBER_NATIVE=ON); -fno-sanitize-recover=all makes an
# undefined-behaviour report abort the test instead of printing and going on. Both build in unity
# batches (CMAKE_UNITY_BUILD: eight files of a target compiled as one), which compiles the Eigen
# templates the files share once a batch instead of once a file; a file's names at namespace
# scope, anonymous namespaces included, must therefore not collide with another file's of the
# same target.
# Not run under a sanitizer, with the reason:
#   - package_installs_and_a_client_builds (label package): it installs the instrumented library
#     and links a client built without the sanitizer's runtime, which cannot link; the code it
#     runs (the README's example) is the World's, which the World tests cover.
#   - the viewer's two rendering tests (viewer_renders_headless, program_view_writes_a_screenshot)
#     run, but without leak checking: a GL library loaded with dlopen and unloaded before exit
#     (Mesa's DRI driver, by every sign) leaves ~5 kB in ~257 allocations that LeakSanitizer cannot
#     name (an unknown module: no suppression can match it); ASan and UBSan still check them.
#   - label `stress` is run (it is the point of a sanitizer run); pass -LE stress to shorten.
#   - the 14 tests that take over 30 s each under ASan (the list below; LIMBER_SANITIZE_ALL=1
#     runs them): ThreadSanitizer still runs the threaded ones among them.
# Installs the test suite's packages and clang (tools/install_packages.sh). Environment:
# LIMBER_SANITIZE_BUILD_DIR overrides build-asan / build-tsan; LIMBER_SKIP_INSTALL=1 skips apt-get.
set -euo pipefail
cd "$(dirname "$0")/.."

mode=address
case "${1:-}" in
  address|thread) mode=$1; shift ;;
  -*|"") ;;
  *) echo "sanitize.sh: unknown mode '$1' (expected address or thread)" >&2; exit 2 ;;
esac

tools/install_packages.sh library tests viewer clang

if [ "$mode" = address ]; then
  sanitize="-fsanitize=address,undefined -fno-sanitize-recover=all"
  build_dir=${LIMBER_SANITIZE_BUILD_DIR:-build-asan}
else
  sanitize="-fsanitize=thread"
  build_dir=${LIMBER_SANITIZE_BUILD_DIR:-build-tsan}
fi
flags="$sanitize -fno-omit-frame-pointer -gline-tables-only"

. tools/progress.sh
stage "sanitizer run ($mode): configuring $build_dir/ (clang 14)"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="$sanitize" -DCMAKE_SHARED_LINKER_FLAGS="$sanitize" \
  -DLIMBER_NATIVE=ON -DLIMBER_BUILD_TESTS=ON -DLIMBER_BUILD_BENCHMARKS=OFF -DCMAKE_UNITY_BUILD=ON >/dev/null

# The sanitizers' runtimes symbolize stacks with llvm-symbolizer, which Debian keeps in llvm-14's folder.
export PATH=/usr/lib/llvm-14/bin:$PATH
if [ "$mode" = address ]; then
  stage "sanitizer run (address): building the suite in $build_dir/ (about 20 min from nothing on 2 cores)"
  quiet_build "$build_dir/build.log" cmake --build "$build_dir" -j2
  stage "sanitizer run (address): the tests"
  # Every report is fatal and exits non-zero; leaks are checked at exit (LeakSanitizer works in
  # this container: it needs ptrace-like access to the process's own threads, which Debian's
  # default allows). new/delete mismatches and container overflows are checked too.
  export ASAN_OPTIONS=halt_on_error=1:abort_on_error=0:detect_leaks=1:check_initialization_order=1:strict_init_order=1:alloc_dealloc_mismatch=1:new_delete_type_mismatch=1:detect_odr_violation=2
  export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
  rendering='^(viewer_renders_headless|program_view_writes_a_screenshot)$'
  # Left to the uninstrumented suite: the tests that take over 30 s each under ASan (14 of them,
  # 835 of its 1400 s), long runs of kernels that faster tests put under it (the same trees,
  # sweeps, layouts and integrators on smaller scenes). LIMBER_SANITIZE_ALL=1 runs them too.
  slow='JointTrees.EverySubstepsBySweepsSettingHoldsFourRagdollsOfThePile|Cli.TheRainsFirstThirtyRagdollsRunAndLand'
  slow+='|JointTrees.TheTreesHoldTheirContactsAtFewSweepsWhateverTheMassRatio|Allocation.JointRowsAllocateNothing'
  slow+='|ColouredRelaxation.JacobiAndGaussSeidelSettleOnTheSameHangingChain<float>'
  slow+='|ColouredRelaxation.ScalarSimdLayoutsAndThreadsGiveTheSameBits<(float|double)>'
  slow+='|featherstone.Integration.QuaternionsStayUnitOverAHundredThousandSteps|RagdollScene.TheActiveRagdollHoldsItsPoseUntilTheBallHitsThenGoesLimp'
  slow+='|VerletMethod.HeavyEndChainKeepsJointsClosedWith100Iterations<float>|RagdollScene.TheBallKnocksItOverUnderEveryMethodThatTakesItAndNoHingeBendsTheWrongWay'
  slow+='|LagrangeThinRods.RungeKuttaWithProjectionConvergesAtItsOrder|Cli.ThePileGivesTheSameTrajectoryBitsForOneOrTwoThreadsAndScalarLanes'
  slow+='|SerialLinks.ParticlesFollowFeatherstone'
  [ "${LIMBER_SANITIZE_ALL:-0}" = 1 ] && slow='^$'
  ctest --test-dir "$build_dir" --output-on-failure -j2 -E "^package_installs_and_a_client_builds\$|$rendering|^($slow)\$" "$@"
  ASAN_OPTIONS=$ASAN_OPTIONS:detect_leaks=0 ctest --test-dir "$build_dir" --output-on-failure -R "$rendering" "$@"
else
  # The tests that start threads, by program (grep the tests for threads =, Threading::,
  # std::thread, --threads); a new threaded test is added here. Only these run: the rest of a
  # program is single-threaded, so ThreadSanitizer has nothing to see in it, and whole programs
  # under it took most of CI's time (verlet_tests alone over 7 min).
  threaded=(
    'threading_tests BlockRunner.*'
    'relaxation_tests *ScalarSimdLayoutsAndThreadsGiveTheSameBits*:*AnEnginesTaskSystemOrTbbArenaGivesTheSameBits*:*HumanoidWithContactsIsTheSameInEveryLayout*'
    'verlet_tests *JointRowsGiveTheSameBitsForOneOrTwoThreads*:*ThePileGivesTheSameBitsScalarAndSimdAndOnOneAndTwoThreads*:*WorkInBothJointModesEveryOrderingAndLayout*'
    'limb_contact_tests *ContactsGiveTheSameBitsForOneOrTwoThreads*'
    'collision_tests *TheNarrowphaseOnThreadsFindsTheSerialContactsBitForBit*'
    'allocation_tests Allocation.JointRowsAllocateNothing:Allocation.EveryRelaxationPathAllocatesNothing:Allocation.TheRattleRuleAllocatesNothing'
    'world_tests World.ADefaultWorldStartsNoThread:World.OnAnEnginesTaskSystemStepsTheSerialBits'
    'cli_tests Cli.EverySolverPathGivesTheSameSummaryOfAChain:Cli.ThePileGivesTheSameTrajectoryBitsForOneOrTwoThreadsAndScalarLanes'
    'featherstone_tests FeatherstoneThreads.*'
  )
  programs=()
  for entry in "${threaded[@]}"; do programs+=("${entry%% *}"); done
  stage "sanitizer run (thread): building the threaded test programs in $build_dir/ (about 7 min from nothing on 2 cores)"
  quiet_build "$build_dir/build.log" cmake --build "$build_dir" -j2 --target "${programs[@]}"
  stage "sanitizer run (thread): the tests"
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tools/sanitize/tsan.supp"
  failed=()
  for entry in "${threaded[@]}"; do
    program=${entry%% *}
    echo "== $program"
    if ! (cd "$build_dir/tests" && "./$program" --gtest_brief=1 "--gtest_filter=${entry#* }" "$@"); then
      failed+=("$program")
    fi
  done
  if [ ${#failed[@]} -gt 0 ]; then
    echo "sanitize.sh: ThreadSanitizer failed in: ${failed[*]}" >&2
    exit 1
  fi
fi
