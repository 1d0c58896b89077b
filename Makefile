# Entry points: `make demo` and `make test` (see README.md). Both install what is missing,
# configure, build with every core, and then run.
JOBS ?= $(shell nproc)
BUILD ?= build

.PHONY: demo test test-long sanitize deps configure build bench clean

demo: build
	./demos/run-default.sh $(BUILD)

# The default suite; `make test-long` runs the whole-scene tests labelled `long`.
test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -LE long

test-long: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -L long

# The default suite built with AddressSanitizer and UndefinedBehaviorSanitizer (build-sanitize/).
SANITIZE_BUILD ?= build-sanitize
sanitize: deps
	cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOCHOR_SANITIZE=ON
	cmake --build $(SANITIZE_BUILD) -j$(JOBS)
	cd $(SANITIZE_BUILD) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j$(JOBS) -LE long

bench: build
	cmake --build $(BUILD) -j$(JOBS) --target isochor_bench
	./$(BUILD)/isochor_bench

deps:
	./tools/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j$(JOBS)

clean:
	rm -rf $(BUILD)
