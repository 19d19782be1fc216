# deform.h (issue 18): tests, example and bench of the deformation part.
C_TESTS += $(B)/test_deform_edit
HAVE_CGAL := $(wildcard /usr/include/CGAL/Surface_mesh_deformation.h)
BENCHES += $(if $(and $(HAVE_CXX),$(HAVE_CGAL),$(HAVE_EIGEN)),$(B)/bench_deform)
# CGAL's side with assertions off (-DNDEBUG); Eigen's headers for its solver
BENCH_FLAGS_deform = -DNDEBUG -DCGAL_NDEBUG -isystem /usr/include/eigen3
BENCH_LIBS_deform =
EXAMPLES += $(B)/deform
