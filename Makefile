# Entry points: `make demo` and `make test` (see README.md). Both install what is missing,
# configure, build with every core, and then run.
JOBS ?= $(shell nproc)
BUILD ?= build

.PHONY: demo test deps configure build bench clean

demo: build
	./demos/run-default.sh $(BUILD)

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

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
