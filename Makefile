# Entry points. `make demo` and `make test` each install what is missing (Debian 12, as root),
# configure, build and run; nothing else is needed on a fresh machine.
BUILD ?= build
ASAN_BUILD ?= build-asan
TSAN_BUILD ?= build-tsan
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
# The sanitizer builds' optimisation and debug info: -O1 with line tables (-g1) is what the ASan and
# libFuzzer documentation recommends, and compiles in about half the time of RelWithDebInfo's -O2 -g
# with the same reports (file and line in every frame). TSan keeps -O2: its suite is CPU-bound.
ASAN_CXX_FLAGS ?= -O1 -g1 -DNDEBUG
# UBSan checks the suite's build leaves to others, which halves its compile time: null, alignment
# and object-size (ASan reports the bad accesses; the fuzzers, built with clang, keep all three
# for the readers) and vptr.
ASAN_SUITE_UNCHECKED ?= vptr,alignment,null,object-size
TSAN_CXX_FLAGS ?= -O2 -g1 -DNDEBUG
JOBS ?= $(shell nproc)
PREFIX ?= /usr/local
CMAKE_FLAGS ?=
# The demo picture: behind and above the sensor, looking ahead along the street.
DEMO_CAMERA ?= --eye -24,-14,13 --target 8,1,-1.5 --fov 65

.PHONY: setup configure build demo test sanitize tsan fuzz accuracy accuracy-sensors accuracy-pcl tiles-memory map-peers install package-check pip-check viewer-check bare-check python clean

setup:
	@bash scripts/setup.sh

configure: setup
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The demo builds the CLI alone (not the tests, benchmarks or Python module it never runs).
demo: configure
	cmake --build $(BUILD) -j $(JOBS) --target lidarsurf_cli
	@mkdir -p $(BUILD)/demo
	$(BUILD)/bin/lidarsurf simulate --scene town --frames 1 -o $(BUILD)/demo/scan.bin --gt $(BUILD)/demo/gt.bin
	$(BUILD)/bin/lidarsurf reconstruct $(BUILD)/demo/scan.bin -o $(BUILD)/demo/mesh.ply
	$(BUILD)/bin/lidarsurf evaluate $(BUILD)/demo/mesh.ply $(BUILD)/demo/gt.bin --json $(BUILD)/demo/metrics.json
	$(BUILD)/bin/lidarsurf render $(BUILD)/demo/mesh.ply -o $(BUILD)/demo/mesh.png $(DEMO_CAMERA)
	@echo "demo: $(BUILD)/demo/mesh.ply (colour by 'level' for k' in MeshLab/CloudCompare), picture $(BUILD)/demo/mesh.png"

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

# The suite under AddressSanitizer + UndefinedBehaviorSanitizer (second build directory), with
# the portable scalar sums (LIDARSURF_SCALAR) where the main build has the SSE2 ones. Left out:
# the tests that run code the others run on more data (accuracy claims, fast path against
# reference path on whole frames, one of two live-mesh dependency settings, the two tile tests
# whose code the other tile tests run, the recordings' CLI script, whose readers the gtests run
# under ASan, the ROS 2 bags' maps, whose readers cli_ros2_readers runs under ASan, the exact
# world's ring hold-out and the live mesh without budget, whose code the other ring hold-out and
# live-mesh tests run, four drives whose carving, orientation, incremental extraction and
# simulated returns the other drives here run: 213 s under ASan, and five carving drives whose
# code the moving car's, the parked car's and the skipped scans' drives run: 251 s under ASan).
# ASAN_EXCLUDE= runs everything.
ASAN_EXCLUDE ?= ^(SeededSurface\.FastPathGivesTheReferenceMesh(InEveryMode|WithDilatedSeeds)|Benchmark\.PaperClaimsHoldOnATownFrame|Pipeline\.AdaptiveGaussianIsMoreAccurateThanImlsOnTheDemo|Reach/LiveMeshReach\.WhatTheCarLeftIsGoneFromTheLiveMesh/EveryDependency|Tiles\.(ScansThatCannotReachATileAreCountedNotIntegrated|TheTilesMeshIsTheWholeMapsMesh)|cli_recordings|cli_ros2$$|cli_recorded_poses$$|RingHoldout\.OddRingsOfAnExactWorldLieOnTheMeshOfTheEvenRings|LiveMesh\.WithoutThresholdOrBudgetItIsTheExactMesh|FreeSpace\.(OfTwoCarsParkedSideBySideTheOneThatStaysIsWhole|IncrementalMeshesEqualTheOnePassMesh|TheRestOfAMostlyCarvedVanGoesWithIt|RaysThatReturnNothingCarveTheUpperSideOfAVanThatLeft|ADarkCarTheWallBehindItAndRandomDropoutsStay|AWalkersPathInFrontOfTheWallIsMostlyCarved|TheMeshLosesTheTrailAndASingleScanIsUnchanged)|Pipeline\.ASequenceOrientsEachSideTowardTheSensorThatSawIt|Simulator\.ReturnsLieOnTheSceneSurface)
sanitize: setup
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO='$(ASAN_CXX_FLAGS)' -DLIDARSURF_SANITIZE=address,undefined -DLIDARSURF_SANITIZE_SKIP='$(ASAN_SUITE_UNCHECKED)' -DLIDARSURF_SCALAR=ON -DLIDARSURF_BUILD_BENCH=OFF -DLIDARSURF_BUILD_PYTHON=OFF
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir $(ASAN_BUILD) --output-on-failure -j $(JOBS) $(if $(ASAN_EXCLUDE),-E '$(ASAN_EXCLUDE)')

# The parallel code under ThreadSanitizer (third build directory): the tests whose code runs TBB
# loops (surface search, reference TSDF, free-space carving, IMLS, metrics, map metrics, simulator,
# renderer, pipeline, the live mesh, the live view's feed and server, a group of tiles' reader), linked
# against Debian's oneTBB source rebuilt with TSan (scripts/build_tbb_tsan.sh: Debian's libtbb is
# not instrumented, and TSan would report every hand-off between its threads as a race).
# Left out: the slowest, which run the same parallel code on more data (the four largest, 290 s
# under TSan), the drives that repeat the carving and extraction other tests here run (about 4
# minutes under TSan), and eight whose threads others here run on their own data (the fast path on a
# KITTI frame as on the town frame, IMLS on a plane, the simulator through the pipeline's scans,
# carving through the moving car's, every mode's TSDF as the thread-count test's, the bridges' two
# searches as the flood fill's, the moving sweep's rays as the simulator's, a
# catch-up's cutting whose threads are the reconstruction's: about 85 s under TSan), and four more
# whose threads others here run (two carving drives as the moving car's, IMLS on a plane as on the
# sphere, the fast path against the reference on the town frame as the flood fill's: 176 s under
# TSan). The TSan build compiles only the test files of these suites
# (tests/CMakeLists.txt, LIDARSURF_TSAN_TEST_SOURCES); scripts/check_test_subset.sh checks that it
# holds every test the filter selects in the full suite of $(BUILD).
TSAN_FILTER ?= SeededSurface.*:Pipeline.*:FreeSpace.*:MapMetrics.*:Imls.*:Metrics.*:Simulator.*:SensorModel.*:Render.*:Benchmark.*:Holdout.*:MarchingCubes.Parallel*:MarchingCubes.Groups*:LiveMesh.Deltas*:VoxelGrid.BatchInsert*:PackedVoxels.BlocksLeftForLater*:LiveFeed.*:LiveServer.*:Tiles.AGroupReadsTheNextScanWhileItFusesOne$\
  -SeededSurface.FastPathGivesTheReferenceMeshInEveryMode:SeededSurface.FastPathGivesTheReferenceMeshWithDilatedSeeds:Benchmark.PaperClaimsHoldOnATownFrame:Pipeline.AdaptiveGaussianIsMoreAccurateThanImlsOnTheDemo$\
:FreeSpace.AWalkersPathInFrontOfTheWallIsMostlyCarved:FreeSpace.TheMeshLosesTheTrailAndASingleScanIsUnchanged:FreeSpace.IncrementalMeshesEqualTheOnePassMesh:FreeSpace.ACarThatLeftLosesWhatRaysReachAndOneParkedAllAlongStays:FreeSpace.TheRestOfAMostlyCarvedVanGoesWithIt:FreeSpace.OfTwoCarsParkedSideBySideTheOneThatStaysIsWhole$\
:Pipeline.ASequenceOrientsEachSideTowardTheSensorThatSawIt:Pipeline.IncrementalExtractionGivesTheMeshOfOneExtraction:Pipeline.ATownDriveFusedFrameByFrameGivesTheOnePassMesh$\
:Pipeline.FastPathGivesTheReferenceMeshOnARealKittiFrame:Imls.ScannedPlaneIsCoveredNearTheSensor:Simulator.ReturnsLieOnTheSceneSurface:FreeSpace.SkippingScansThatReachNothingIsCarvingThem$\
:Pipeline.EveryModeProducesASurfaceNearTheScene:SeededSurface.BridgesAreTheSameInBothSearches:Simulator.ASweepThatTakesTimeCastsEachRayFromWhereTheRigIsThen:LiveFeed.ACatchUpIsCutIntoMessagesOfTheSizeAsked$\
:FreeSpace.RaysThatReturnNothingCarveTheUpperSideOfAVanThatLeft:FreeSpace.ADarkCarTheWallBehindItAndRandomDropoutsStay:Imls.PlaneMeshLiesOnThePlane:SeededSurface.FastPathGivesTheReferenceMeshOnATownFrame
tsan:
	@bash scripts/setup.sh tsan
	bash scripts/build_tbb_tsan.sh $(TSAN_BUILD)/tbb
	cmake -S . -B $(TSAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO='$(TSAN_CXX_FLAGS)' -DLIDARSURF_SANITIZE=thread -DLIDARSURF_BUILD_BENCH=OFF -DLIDARSURF_BUILD_PYTHON=OFF -DTBB_DIR=$(CURDIR)/$(TSAN_BUILD)/tbb/lib/cmake/TBB
	cmake --build $(TSAN_BUILD) -j $(JOBS) --target lidarsurf_tests
	bash scripts/check_test_subset.sh $(BUILD)/tests/lidarsurf_tests $(TSAN_BUILD)/tests/lidarsurf_tests '$(TSAN_FILTER)'
	TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$(CURDIR)/scripts/tsan.supp" $(TSAN_BUILD)/tests/lidarsurf_tests --gtest_filter='$(TSAN_FILTER)'

# libFuzzer harnesses (clang, ASan+UBSan) run FUZZ_SECONDS each on fuzz/corpus/; see docs/reliability.md.
fuzz:
	@bash scripts/setup.sh fuzz
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO='$(ASAN_CXX_FLAGS)' -DLIDARSURF_BUILD_FUZZERS=ON -DLIDARSURF_SANITIZE=address,undefined -DLIDARSURF_BUILD_TESTS=OFF -DLIDARSURF_BUILD_BENCH=OFF -DLIDARSURF_BUILD_PYTHON=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target lidarsurf_fuzzers
	bash scripts/run_fuzzers.sh $(FUZZ_BUILD)/fuzz $(FUZZ_SECONDS)

# The accuracy benchmark against the true scene and the meshers users already have (Open3D from
# Debian's python3-open3d), docs/benchmarks.md: about 25 minutes for 10 frames on 2 cores.
ACCURACY_DIR ?= $(BUILD)/accuracy
ACCURACY_FRAMES ?= 10
accuracy: build
	@bash scripts/setup.sh peers
	$(BUILD)/bin/lidarsurf simulate --scene town --frames $(ACCURACY_FRAMES) -o $(ACCURACY_DIR)/town
	/usr/bin/python3 scripts/peers_open3d.py $(ACCURACY_DIR)/town
	$(BUILD)/bin/lidarsurf benchmark $(ACCURACY_DIR)/town --peers $(ACCURACY_DIR)/town/peers --out $(ACCURACY_DIR)/table
	$(BUILD)/bin/lidarsurf benchmark $(ACCURACY_DIR)/town --ablation --no-plots --out $(ACCURACY_DIR)/ablation

# Every sensor preset on the town and the off-road scene (docs/benchmarks.md, "Every lidar"): the
# default, the paper's AN+GC and the Open3D peers on the same frames, within 30 m. PCL joins with
# PCL_PEER=$(PCL_BUILD)/bin/lidarsurf_pcl_peer after `make accuracy-pcl`.
SENSORS_DIR ?= $(BUILD)/accuracy-sensors
# Long drives fused whole and in tiles: peak memory and time (docs/benchmarks.md, "Long drives in tiles").
TILES_DIR ?= $(BUILD)/tiles
tiles-memory: build
	bash scripts/tiles_memory.sh $(BUILD)/bin/lidarsurf $(TILES_DIR)

accuracy-sensors: build
	@bash scripts/setup.sh peers
	bash scripts/accuracy_sensors.sh $(BUILD)/bin/lidarsurf $(SENSORS_DIR)

# PCL's MLS + greedy projection as one more peer (PCL is heavy: its own build directory, not in make
# test). Run after `make accuracy`, then re-run its benchmark line to get the PCL row.
PCL_BUILD ?= build-pcl
accuracy-pcl:
	@bash scripts/setup.sh pcl
	cmake -S . -B $(PCL_BUILD) -DCMAKE_BUILD_TYPE=Release -DLIDARSURF_BUILD_PCL_PEER=ON -DLIDARSURF_BUILD_TESTS=OFF -DLIDARSURF_BUILD_BENCH=OFF -DLIDARSURF_BUILD_PYTHON=OFF
	cmake --build $(PCL_BUILD) -j $(JOBS) --target lidarsurf_pcl_peer
	$(PCL_BUILD)/bin/lidarsurf_pcl_peer $(ACCURACY_DIR)/town $(ACCURACY_DIR)/town/peers
	$(BUILD)/bin/lidarsurf benchmark $(ACCURACY_DIR)/town --methods default --peers $(ACCURACY_DIR)/town/peers --no-plots --out $(ACCURACY_DIR)/table-pcl

# VDBFusion as a peer of the map benchmark (OpenVDB: its own build directory, not in make test). Its
# core is extracted from ../shared/peers into the build directory; then
#   lidarsurf map-benchmark DRIVE --vdbfusion $(PEERS_BUILD)/bin/lidarsurf_vdbfusion_peer --rows ...
PEERS_BUILD ?= build-peers
VDBFUSION_ARCHIVE ?= $(firstword $(wildcard ../shared/peers/vdbfusion-core-*.tar.gz))
map-peers:
	@bash scripts/setup.sh vdbfusion
	@test -n "$(VDBFUSION_ARCHIVE)" || { echo "no VDBFusion archive: set VDBFUSION_ARCHIVE=path/to/vdbfusion-core-*.tar.gz"; exit 2; }
	mkdir -p $(PEERS_BUILD)/vdbfusion-src
	tar -xzf $(VDBFUSION_ARCHIVE) -C $(PEERS_BUILD)/vdbfusion-src
	cmake -S . -B $(PEERS_BUILD) -DCMAKE_BUILD_TYPE=Release -DLIDARSURF_BUILD_VDBFUSION_PEER=ON -DVDBFUSION_SOURCE_DIR=$(CURDIR)/$(PEERS_BUILD)/vdbfusion-src/src/vdbfusion/vdbfusion -DLIDARSURF_BUILD_TESTS=OFF -DLIDARSURF_BUILD_BENCH=OFF -DLIDARSURF_BUILD_PYTHON=OFF
	cmake --build $(PEERS_BUILD) -j $(JOBS) --target lidarsurf_vdbfusion_peer

# The Python package in the build tree: PYTHONPATH=$(BUILD)/python /usr/bin/python3 -c 'import lidarsurf'
python: build
	@echo "use: PYTHONPATH=$(CURDIR)/$(BUILD)/python /usr/bin/python3 python/examples/reconstruct.py"

install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

# Installs into a scratch prefix and builds a consumer with find_package(lidarsurf), then the
# README's CMake and C++ snippets as a user's project (timed), run on a scan.
package-check: build
	rm -rf $(BUILD)/pkg-prefix $(BUILD)/pkg-consumer
	cmake --install $(BUILD) --prefix $(BUILD)/pkg-prefix
	bash tests/package/check_installed.sh $(BUILD)/pkg-prefix $(BUILD)
	cmake -S tests/package -B $(BUILD)/pkg-consumer -DCMAKE_PREFIX_PATH=$(CURDIR)/$(BUILD)/pkg-prefix
	cmake --build $(BUILD)/pkg-consumer
	$(BUILD)/pkg-consumer/consumer
	$(BUILD)/pkg-consumer/consumer_sim
	$(BUILD)/pkg-consumer/consumer_recording
	bash tests/package/readme_consumer.sh $(BUILD)

# The viewer's pages in headless Chromium (Debian's chromium and, to drive it, playwright-core and
# the glTF validator from npm, all installed by `setup.sh viewer`): the page `lidarsurf view` writes, coloured by height and
# by level (scripts/viewer_check.sh); the live view of `fuse --serve` on a short drive, mid-drive,
# later and final, the page's final mesh against fuse's output (scripts/live_view_check.sh); binary
# glTF of a scan, a map and a tiled map through the Khronos validator and three.js's GLTFLoader and
# DRACOLoader (scripts/gltf_check.sh).
viewer-check: build
	@bash scripts/setup.sh viewer
	bash scripts/viewer_check.sh $(BUILD)/bin/lidarsurf $(CURDIR)/$(BUILD)/viewer-check
	bash scripts/live_view_check.sh $(BUILD)/bin/lidarsurf $(CURDIR)/$(BUILD)/live-view-check
	bash scripts/gltf_check.sh $(BUILD)/bin/lidarsurf $(BUILD)/python $(CURDIR)/$(BUILD)/gltf-check

# A clone built as a new user builds it (plain cmake, no setup.sh, so no three.js): the CLI builds
# with the viewer left out, and `lidarsurf view` and `fuse --serve` exit 2 saying how to add it.
bare-check:
	JOBS=$(JOBS) bash scripts/bare_build_check.sh $(CURDIR)/$(BUILD)/bare-check

# The Python package as pip builds and installs it, offline: a wheel from pyproject.toml, installed
# into a fresh venv (--system-site-packages) and for the system Python; the README's Python lines
# run against each install (scripts/pip_check.sh).
pip-check: setup
	bash scripts/pip_check.sh $(CURDIR)/$(BUILD)/pip-check

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
