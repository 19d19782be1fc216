# examples/render.h's image readers and examples/relief.h (issue 17 point 5, issue 20): tests, the PNG
# fuzz target (built by the Makefile's fuzz_% rules through FUZZ_FMTS), the libpng reference test.
HAVE_LIBPNG := $(wildcard /usr/include/png.h)
C_TESTS   += $(B)/test_image $(B)/test_relief
FUZZ_FMTS += png
REF_TESTS += $(if $(and $(HAVE_CXX),$(HAVE_LIBPNG)),$(B)/ref_png)

$(B)/ref_png: tests/ref_png.cpp $(ALLDEPS) | $(B)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ -lpng -lz -lm
EXAMPLES  += $(B)/relief
BENCHES   += $(if $(and $(HAVE_CXX),$(HAVE_OSMESA)),$(B)/bench_relief)
BENCH_LIBS_relief = -lOSMesa
# test_relief --cli runs the program (tests.list: relief_cli), so building the test builds it too
$(B)/test_relief: | $(B)/relief
