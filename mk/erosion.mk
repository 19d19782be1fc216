# erosion.h (issue 17): the tests
C_TESTS += $(B)/test_erosion
