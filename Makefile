# Entry points: `make demo` and `make test` (see README.md). Both install what is missing,
# configure, build with every core, and then run.
JOBS ?= $(shell nproc)
BUILD ?= build

.PHONY: demo test test-long test-mpi sanitize deps configure build bench clean format format-check docs

demo: build
	./demos/run-default.sh $(BUILD)

# The default suite; `make test-long` runs the whole-scene tests labelled `long`. One test more
# than cores at a time: the browser, pip and study tests spend much of their time waiting (on 2
# cores: 236 s against 264 s at -j2, every test the same).
test: build
	cd $(BUILD) && ctest --output-on-failure -j$$(( $(JOBS) + 1 )) -LE long

# The key tables of docs/scenes.md and docs/studies.md, rewritten from the key rows
# (core/src/scene_keys.cpp, apps/src/study_keys.cpp); SceneKeys.TheDocsKeyTablesAreGeneratedFromTheKeyTables
# fails until they are.
docs: build
	$(BUILD)/isochor keys --docs docs/scenes.md
	$(BUILD)/isochor keys --study --docs docs/studies.md

test-long: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -L long

# MPI (CI runs it): one scene on 2 and 3 ranks against one process (tests/run_mpi.sh), and the
# MPI study executor against the local one.
test-mpi: build
	cd $(BUILD) && ctest --output-on-failure -L mpi

# The default suite's unit tests and the fuzz tests, built with AddressSanitizer and
# UndefinedBehaviorSanitizer (build-sanitize/); the whole-scene tests that take minutes under
# the sanitizers are left out (SANITIZE_SKIP; also the documentation check that meshes every demo,
# the scanned models included, which the default suite runs). Suppressions for Debian's libraries:
# tests/sanitize/.
SANITIZE_BUILD ?= build-sanitize
SANITIZE_SKIP ?= ^(Study\.|BackwardEulerRun\.PcgStoppedEarlyKeepsTheSteps|OptimisationStep\.FactorReuseTakesAboutExactNewtonsIterations|Xpbd\.IncompressibleStretch|Xpbd\.ApproachesTheIda|Statics\.TheSameEquilibria|Statics\.PressureCube|Statics\.UnhAndSnh|cli\.interrupt_and_resume|IdaRun\.BallDropFramesAgree|MassSpring\.SqueezedBall|BallDrop\.|Skeleton\.ArmStarting|Ggl\.SolversOnJacobiansCaptured|SeedScenes\.|Scene\.EveryKeyReadByTheDemosIsDocumented)
sanitize: deps
	cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DISOCHOR_SANITIZE=ON \
	  -DISOCHOR_FUZZ_ITERATIONS=500 -DISOCHOR_FUZZ_SCENES=120
	cmake --build $(SANITIZE_BUILD) -j$(JOBS)
	cd $(SANITIZE_BUILD) && \
	  ASAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize/asan.supp \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize/lsan.supp:print_suppressions=0 \
	  UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j$(JOBS) -LE long -E '$(SANITIZE_SKIP)'

bench: build
	cmake --build $(BUILD) -j$(JOBS) --target isochor_bench
	./$(BUILD)/isochor_bench

# The C++ style (.clang-format): format-check fails on any tracked source that clang-format would
# change (tests/data/ holds inputs made to be bad and is left alone); format rewrites them.
FORMAT_FILES = git ls-files '*.cpp' '*.hpp' ':!tests/data/'
format-check:
	$(FORMAT_FILES) | xargs clang-format --dry-run -Werror

format:
	$(FORMAT_FILES) | xargs clang-format -i

deps:
	./tools/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j$(JOBS)

clean:
	rm -rf $(BUILD)
