# subdiv4.h (issue 21 point 4): its fuzz target, built as $(B)/fuzz_subdiv4 (replayed on
# tests/fuzz/corpus/subdiv4 by tests.list's fuzz_regress_subdiv4) and by `make fuzz` with libFuzzer.
FUZZ_FMTS += subdiv4
