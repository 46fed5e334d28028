# The two commands of the README wrap CMake:
#   make demo   install what is missing, build, run the demo on the default OpenCL device
#   make test   install what is missing, build, run the whole test suite, then the hardening run
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
ifeq ($(CI),true)
  CMAKE_FLAGS += -DSTEX_WERROR=ON
endif

.PHONY: all deps configure build demo test fuzz sanitize clean
all: build

deps:
	@./scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS) > $(BUILD).configure.log 2>&1 || (cat $(BUILD).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

demo: build
	@./scripts/demo.sh $(BUILD)

# The whole suite on PoCL, then the device tests again on Mesa rusticl's llvmpipe device (ctest label llvmpipe;
# both run, and the target fails if either did), then the hardening run (docs/hardening.md): the suite again
# under ASan + UBSan in the clang tree build-san and a bounded libFuzzer run per target. HARDENING=0 skips the
# hardening run (a quick local run).
HARDENING ?= 1
test: build
	@cd $(BUILD) && { rc=0; ctest --output-on-failure -j $(JOBS) -LE llvmpipe || rc=1; \
	  ctest --output-on-failure -j $(JOBS) -L llvmpipe || rc=1; exit $$rc; }
ifneq ($(HARDENING),0)
	@./scripts/ci-hardening.sh
endif

# Hardening (docs/hardening.md): bounded libFuzzer runs and the ASan+UBSan test suite, both in the shared
# clang tree build-san (scripts/san-configure.sh). FUZZ_SECONDS and SANITIZE_AREAS tune them.
fuzz: deps
	@./scripts/fuzz.sh

sanitize: deps
	@./scripts/sanitize.sh

clean:
	rm -rf $(BUILD) $(BUILD).configure.log
