# Entry points: `make demo` and `make test` (see README.md). Both install what is missing,
# configure, build with every core, and then run.
JOBS ?= $(shell nproc)
BUILD ?= build

.PHONY: demo test test-long deps configure build bench clean

demo: build
	./demos/run-default.sh $(BUILD)

# The default suite; `make test-long` runs the whole-scene tests labelled `long`.
test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -LE long

test-long: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -L long

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
