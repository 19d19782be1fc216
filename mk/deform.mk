# deform.h (issue 18): tests, example and bench of the deformation part.
C_TESTS += $(B)/test_deform_edit
