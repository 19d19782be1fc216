# tests/test_dispmesh_catch.c (issue 21 point 8): QEM placement and baked depth against closed-form values
C_TESTS += $(B)/test_dispmesh_catch
