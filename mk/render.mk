# examples/render.h (issue 21 point 4): its drawing entry points' fuzz target, built as $(B)/fuzz_render
# (replayed on tests/fuzz/corpus/render by tests.list's fuzz_regress_render) and by `make fuzz` with
# libFuzzer. The image readers have their own target (fuzz_png, mk/relief.mk).
FUZZ_FMTS += render
