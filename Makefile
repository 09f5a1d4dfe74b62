# Thin wrappers over CMake presets. The two commands of the README:
#   make run    install dependencies, build, run companiond on the simulated world (SCENARIO=...)
#   make test   install dependencies, build, run every test (ThreadSanitizer pass included)
.PHONY: run test deps build bench eval train fuzz format tidy clean

JOBS ?= $(shell nproc)
TSAN_TARGETS := test_core_channel test_hal_clock test_firmware_executor test_firmware_daemon \
  test_drivers_amfitrack_threads test_sim_realtime
FUZZERS := fuzz_candump_line fuzz_slcan_stream fuzz_scout_decode fuzz_amfiprot fuzz_vlp16 \
  fuzz_pedestrian_dataset fuzz_voxel_grid
FUZZ_SECONDS ?= 10
# Per input: longer is a hang (a finding if it repeats when the input runs alone).
FUZZ_TIMEOUT_S := 10

deps:
	@bash toolchain/install-deps.sh

build: deps
	@cmake --preset dev > /dev/null
	@cmake --build --preset dev -j $(JOBS)

SCENARIO ?= static_obstacle
run: deps
	@cmake --preset dev > /dev/null
	@cmake --build --preset dev -j $(JOBS) --target companiond
	@mkdir -p build/run
	./build/dev/firmware/companiond --config config/sim.yaml --scenario $(SCENARIO) --live \
	  --log-sink console --status-file build/run/status.json --report build/run/report

test: build
	@cmake --preset tsan > /dev/null
	@cmake --build --preset tsan -j $(JOBS) --target $(TSAN_TARGETS)
	@echo "== ThreadSanitizer: concurrency tests =="
	@ctest --test-dir build/tsan -L concurrency --output-on-failure -j $(JOBS)
	@$(MAKE) --no-print-directory fuzz FUZZ_SECONDS=$(FUZZ_SECONDS)
	@echo "== all tests =="
	@ctest --preset dev -j $(JOBS)

bench: deps
	@cmake --preset release -DCOMPANION_BUILD_BENCH=ON > /dev/null
	@cmake --build --preset release -j $(JOBS) --target bench_core bench_scheduler bench_tracker bench_lidar bench_control

# The full evaluation of docs/EVALUATION.md (sim/eval/run_benchmark.sh; 2 h 15 min on 2 cores, twenty-fourth session; STEPS=... runs it in sittings).
EVAL_OUT ?= eval-full
eval: deps
	@cmake --preset release > /dev/null
	@cmake --build --preset release -j $(JOBS) --target companion-eval
	sim/eval/run_benchmark.sh $(EVAL_OUT)

# PPO training of the learned selector (sim/training; LibTorch): writes TRAIN_OUT for policy.file
# (docs/eval/SESSIONS.md, "The learned policy").
TRAIN_OUT ?= build/policy.bin
TRAIN_STEPS ?= 1000000
TRAIN_ARGS ?=
train:
	@bash toolchain/install-deps.sh --training
	@cmake --preset release -DCOMPANION_BUILD_TRAINING=ON > /dev/null
	@cmake --build --preset release -j $(JOBS) --target companion-train
	./build/release/sim/companion-train --out $(TRAIN_OUT) --steps $(TRAIN_STEPS) --log $(TRAIN_OUT).csv $(TRAIN_ARGS)

# Coverage-guided fuzzing of the decoders (clang + libFuzzer), FUZZ_SECONDS each, starting from
# the seed corpora in tests/fuzz/corpus (copied: the repository is not modified). A crash, leak or
# out-of-memory input fails it, and so does a timeout that repeats when its input is run alone
# (toolchain/fuzz_findings.sh: one that does not was the machine stalling); the input is kept.
fuzz: deps
	@cmake --preset fuzz > /dev/null
	@cmake --build --preset fuzz -j $(JOBS) --target $(FUZZERS)
	@set -e; work=$$(mktemp -d); for f in $(FUZZERS); do \
	  mkdir -p $$work/$$f && cp tests/fuzz/corpus/$$f/* $$work/$$f/; \
	  echo "== fuzz $$f ($(FUZZ_SECONDS) s) =="; \
	  build/fuzz/tests/fuzz/$$f -max_total_time=$(FUZZ_SECONDS) -timeout=$(FUZZ_TIMEOUT_S) \
	    -print_final_stats=0 -artifact_prefix=$$work/ $$work/$$f 2>&1 \
	    | grep -E "DONE|ERROR|SUMMARY" || true; \
	  if ! toolchain/fuzz_findings.sh build/fuzz/tests/fuzz/$$f $$work $(FUZZ_TIMEOUT_S); then \
	    echo "fuzz $$f: failing input kept in $$work"; exit 1; fi; \
	done; rm -rf $$work

format:
	@git ls-files '*.cpp' '*.hpp' | xargs clang-format -i

tidy: build
	@git ls-files 'hal/*.cpp' 'core/*.cpp' 'firmware/*.cpp' | xargs clang-tidy -p build/dev --quiet

clean:
	rm -rf build
