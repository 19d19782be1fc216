# texel.h (issue 19): tests
C_TESTS += $(B)/test_texel $(B)/test_texel_tvt
