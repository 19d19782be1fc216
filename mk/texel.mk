# texel.h (issue 19): tests and the grass example
C_TESTS += $(B)/test_texel $(B)/test_texel_tvt
EXAMPLES += $(B)/grass
