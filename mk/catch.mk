# tests/test_dispmesh_catch.c (issue 21 point 8): QEM placement and baked depth against closed-form values
# tests/test_dispmesh_hostile.c (issue 21 point 2): far hits, the public param and map arrays, 1e17 coordinates, sample bound
C_TESTS += $(B)/test_dispmesh_catch
C_TESTS += $(B)/test_dispmesh_hostile
