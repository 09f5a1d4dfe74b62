# Thin wrappers over CMake presets. The two commands of the README:
#   make run    install dependencies, build, run companiond (built-in defaults / simulated world)
#   make test   install dependencies, build, run every test (ThreadSanitizer pass included)
.PHONY: run test deps build bench format tidy clean

JOBS ?= $(shell nproc)
TSAN_TARGETS := test_core_channel test_hal_clock test_firmware_executor test_firmware_daemon

deps:
	@bash toolchain/install-deps.sh

build: deps
	@cmake --preset dev > /dev/null
	@cmake --build --preset dev -j $(JOBS)

run: deps
	@cmake --preset dev > /dev/null
	@cmake --build --preset dev -j $(JOBS) --target companiond
	./build/dev/firmware/companiond --config config/companiond.yaml --log-sink console

test: build
	@cmake --preset tsan > /dev/null
	@cmake --build --preset tsan -j $(JOBS) --target $(TSAN_TARGETS)
	@echo "== ThreadSanitizer: concurrency tests =="
	@ctest --test-dir build/tsan -L concurrency --output-on-failure -j $(JOBS)
	@echo "== all tests =="
	@ctest --preset dev -j $(JOBS)

bench: deps
	@cmake --preset release -DCOMPANION_BUILD_BENCH=ON > /dev/null
	@cmake --build --preset release -j $(JOBS) --target bench_core bench_scheduler

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

tidy: build
	@git ls-files 'hal/*.cpp' 'core/*.cpp' 'firmware/*.cpp' | xargs clang-tidy -p build/dev --quiet

clean:
	rm -rf build
