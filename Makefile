# The two commands: `make run` lints the shipped model, `make test` runs the whole test suite.
# Both fetch MuJoCo 3.17.0 (from the official `mujoco` wheel on PyPI) into .mujoco/ on first use.
MUJOCO := .mujoco/lib/libmujoco.so
CARGO ?= cargo

.PHONY: run test build lint bench docs clean-mujoco test-install

$(MUJOCO): scripts/setup-mujoco.sh
	./scripts/setup-mujoco.sh

build: $(MUJOCO)
	$(CARGO) build --release --locked

# Exit code 1 only means "findings were reported"; make fails only on exit 2 (modellint could not run).
run: build
	@./target/release/modellint models/asimov.xml; s=$$?; [ $$s -le 1 ]

# Formatting and clippy, warnings as errors (.ci/run runs this before `make test`). Clippy needs
# .mujoco/ too: mujoco-rs links libmujoco at build time. Clippy runs in the release profile: its
# build scripts (zstd-sys's C build among them) and proc-macro crates are then the same artifacts
# `make test` uses, built once instead of once per profile (76 such units of a fresh check).
lint: $(MUJOCO)
	$(CARGO) fmt --all --check
	$(CARGO) clippy --release --all-targets --locked -- -D warnings

test: $(MUJOCO)
	@[ -d ../shared/data ] || echo "modellint: ../shared/data is absent: tests on the real Menagerie models and BAM logs print 'skipping' and pass without checking (run with -- --nocapture to see them)"
	$(CARGO) test --release --locked

# The Python package (wheel in a fresh venv) and the pre-commit hook, end to end (.ci/run runs them).
test-install: build
	./scripts/test-wheel.sh
	./scripts/test-precommit.sh

bench: build
	./bench/run.sh

docs: build
	./target/release/modellint gen-docs --out docs/rules

clean-mujoco:
	rm -rf .mujoco
