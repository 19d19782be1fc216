/* deform.h - v0.2 - MIT licence or public domain (see end of file)
   Mesh editing by dragging a handle inside a region of interest (ROI): plain Laplacian editing,
   Laplacian editing with fitted per-vertex similarities, and linear rotation-invariant (LRI)
   coordinates, with a built-in sparse Cholesky factorization (no dependency). The setup factors
   once per ROI and handle; each frame is a few triangular solves.

   HOW TO USE (in ten lines)
       // in exactly one C or C++ file, #define DFM_IMPLEMENTATION before #include "deform.h"
       dfm_deform_options o = dfm_deform_default_options();
       o.method = DFM_METHOD_LRI;                  // or DFM_METHOD_LAPLACIAN, DFM_METHOD_FITTING
       dfm_deform *d;                              // roi[v], handle[v]: nonzero = member
       if (dfm_deform_setup(pos, nv, tris, nt, roi, handle, &o, &d) != DFM_OK) return 1;
       dfm_pose_identity(pos, nv, targets, rotations);           // everything where it is,
       dfm_pose_twist(pos, nv, handle, point, axis, angle, targets, rotations); // then the handle
       dfm_deform_solve(d, targets, rotations, out);             // per frame: out = new positions
       dfm_deform_free(d);

   PART 1: DEFORMATION
     WHAT
       positions are 3 doubles a vertex, triangles 3 uint32_t indices. The ROI's vertices move;
       the handle's (a subset of the ROI) follow the caller's targets; every other vertex is fixed
       where the caller's targets put it (usually where it is), and so is a vertex in no
       triangle. All three methods solve for the displacement x' - x, in the least-squares sense,
       of
         LAPLACIAN  (L x')_i = delta_i = (L x)_i for every vertex whose 1-ring holds an unknown,
                    L_i x = x_i - sum_j w_ij x_j / sum_j w_ij (the thesis's L for uniform weights);
         FITTING    (L x')_i = T_i delta_i with T_i = s_i I + [h_i]x, the linearized similarity
                    fitted (linearly in x') to vertex i's closed 1-ring on centred coordinates:
                    s_i = sum_j q_j . x'_j / sum |q_j|^2, h_i = S_i^-1 sum_j q_j x x'_j, q_j = x_j -
                    centroid, S_i = sum (|q_j|^2 I - q_j q_j^T); x, y, z coupled (3x3 blocks);
         LRI        per vertex the frame F_i = [b1 b2 N] (N: area-weighted normal; b1: a tangent
                    edge direction; b2 = N x b1); first the frames: F'_j = F'_i R_ij, R_ij =
                    F_i^T F_j, per edge, with the handle's and fixed frames set to R F; then the
                    positions: x'_j - x'_i = (F'_i c_ij - F'_j c_ji) / 2 per edge, c_ij =
                    F_i^T (x_j - x_i). The frames are solved in M_i = F'_i F_i^T (F'_i = M_i F_i):
                    the row F'_j - F'_i R_ij equals (M_j - M_i) F_j, of the same length as
                    M_j - M_i, so the thesis's 3n x 3n frames system is the graph Laplacian of
                    M's 9 entries (M = R at the handle, I at the fixed vertices), the same matrix
                    as the positions system with uniform weights: one factorization serves both.
       The handle's rotations (9 doubles a vertex) are read by LRI only: a translation-only drag
       leaves LRI's frames unturned (the known weakness of linear methods, the thesis's Fig 3-4).
       Helpers: dfm_weld (the pre-pass for triangle soups), dfm_roi_rings (k rings around a
       mask), dfm_roi_geodesic (edge-path distance from seeds), dfm_rotation, and the poses
       dfm_pose_identity / _rigid (translate, rotate) / _twist / _bend, which fill targets and
       rotations for a mask. LRI's rotations can be followed by as-rigid-as-possible steps
       (rigid_steps) that fit them to the solved positions.
     OPTIONS (dfm_deform_options; zeroed or NULL = defaults, dfm_deform_default_options())
       method             DFM_METHOD_LAPLACIAN (0), DFM_METHOD_FITTING, DFM_METHOD_LRI.
       weights            DFM_WEIGHTS_UNIFORM (0: w_ij = 1, the thesis) or DFM_WEIGHTS_COTAN
                          (w_ij = (cot a + cot b) / 2, clamped below at 1e-3; LRI weights its
                          position rows by sqrt(w_ij)).
       handle_constraint  DFM_HANDLE_HARD (0): the handle is eliminated and lands exactly on its
                          targets; DFM_HANDLE_SOFT: the thesis's rows w |x'_h - u_h|^2 (and
                          w |F'_h - R F_h|^2 for LRI), so the handle is solved too. Fixed vertices
                          are always eliminated.
       handle_weight      w of the soft rows (0 = 1, the thesis's implicit weight).
       frames             LRI: DFM_FRAMES_FIRST_EDGE (0: b1 from the lowest-numbered neighbour)
                          or DFM_FRAMES_MAX_ELEVATION (the thesis's ch. 4 "principal direction":
                          the neighbour edge of largest elevation angle, most below the tangent
                          plane).
       orthonormalize     LRI, the solved frames of the unknowns before the positions solve:
                          DFM_ORTHO_NONE (0), DFM_ORTHO_POLAR (the closest rotation, scaled
                          Newton iteration), DFM_ORTHO_GRAM_SCHMIDT (N first, then b1).
       refine_steps       iterative refinement steps per solve (0: none).
       rigid_steps        LRI: as-rigid-as-possible steps after the LRI solve (0: none, the
                          thesis; at most 100). Each step fits every unknown's rotation to the
                          solved positions (R_i maximizing tr(R^T sum_j w_ij e'_ij e_ij^T), started
                          from its LRI rotation) and solves the positions system again with the
                          same factor: one 3-column solve a step, 9 doubles an unknown. See
                          DECISIONS.
       allocator, progress, progress_user: as in part 2; progress runs during the setup only.
     WHEN THE FRAME CHOICE CHANGES THE RESULT
       Only with DFM_ORTHO_GRAM_SCHMIDT. Choosing another b1 replaces F_i by F_i Q_i (Q_i a turn
       about N); M_i = F'_i F_i^T does not change, and F'_i c_ij = M_i (x_j - x_i), so with no
       orthonormalization, or the polar factor (polar(M F) = polar(M) F), the positions are the
       same to rounding. Gram-Schmidt treats N and b1 unequally, so there the choice matters.
       The thesis's ch. 4 figures cannot come from the frame choice alone; this header offers it
       for fidelity.
     MEMORY
       The object holds the positions, the mesh graph, the rows (LAPLACIAN: 12 bytes a term,
       about 7 terms a vertex; FITTING: 76 bytes a term; LRI: two rows an edge, and one factor
       for both systems with uniform weights, two with cotangent ones), the factors
       (dfm_deform_get_info: bytes, nnz_l; the normal matrices only with refine_steps > 0), and
       18 doubles a vertex of per-frame workspace (and 9 an unknown for LRI's rigid steps).
       During the setup a normal matrix and its factor are held at once. dfm_deform_solve
       allocates only inside dfm_chol_solve; its cost follows the ROI and its neighbours, not the
       mesh (but for one copy of the targets).
     ERRORS
       dfm_deform_setup: DFM_ERR_INVALID_ARGUMENT (NULL, an option out of range, no triangles),
       DFM_ERR_BAD_INDEX (an index >= vertex_count), DFM_ERR_BAD_VALUE (NaN/Inf position, negative
       or NaN weight), DFM_ERR_EMPTY_ROI (no ROI vertex outside the handle),
       DFM_ERR_HANDLE_OUTSIDE_ROI, DFM_ERR_UNCONSTRAINED (a connected part of the unknowns touches
       no fixed vertex and no soft handle: its translation would be free), DFM_ERR_DEGENERATE_TRIANGLE
       (zero area, 1e-12 relative, or a repeated index, in a triangle touching the unknowns),
       DFM_ERR_NON_MANIFOLD (an edge in more than two triangles, anywhere in the mesh),
       DFM_ERR_UNWELDED (two used vertices at exactly the same position: dfm_weld first),
       DFM_ERR_NOT_POSITIVE_DEFINITE (a singular system the checks above did not catch, e.g. a
       fitting ROI held by collinear vertices only), DFM_ERR_NOT_FINITE (finite positions whose
       system still overflows after the rescaling of DECISIONS), DFM_ERR_TOO_LARGE, DFM_ERR_OUT_OF_MEMORY, DFM_CANCELLED. On failure *out is NULL and
       nothing is leaked.
       dfm_deform_solve: DFM_ERR_INVALID_ARGUMENT (NULL), DFM_ERR_BAD_VALUE (a NaN/Inf target or
       rotation where one is read), DFM_ERR_NOT_FINITE (finite targets, but a displacement or a
       result overflowed, e.g. targets near 1e308; out is not written), DFM_ERR_OUT_OF_MEMORY;
       the object stays usable.
       dfm_roi_geodesic: DFM_ERR_NOT_FINITE when an edge length overflows (coordinates near 1e308).
       The void helpers (dfm_rotation, dfm_pose_*) compute in doubles what they are given and
       check nothing: a pose beyond 1e308 is refused by dfm_deform_solve.
     THREAD SAFETY
       No global state. dfm_deform_solve uses the object's workspace: one thread per object at a
       time. Results are deterministic (the same input gives the same bits).
     LIMITS
       Linear methods: the Laplacian keeps its delta_i unturned (rotations shrink and shear the
       detail), fitting handles small rotations only (s I + [h]x is not a rotation; large angles
       scale), LRI needs the handle's rotation given. One solve cannot turn the handle by 180
       degrees or more: a rotation matrix carries no turn count (720 degrees is I), and LRI's
       linear frames solve averages the fixed frames and the turned ones, which is singular at
       180 degrees; larger turns need several solves, each set up on the previous result. At
       most (2^31 - 1) / 9 vertices. The whole mesh is checked for non-manifold edges and unwelded
       vertices, the ROI's neighbourhood for degenerate triangles.
       The same bits whatever the compiler's FMA contraction setting, except under clang's
       -ffp-contract=fast (see part 2's LIMITS).
     DECISIONS
       - A mesh whose largest coordinate (over the vertices in triangles) is above 2^100 or below
         2^-100 is scaled by a power of two into [0.5, 1) for the setup, and the targets and
         results of each solve with it (exact, so the methods stay scale-free from 1e-300 to
         1e300; meshes in between keep their bits): the sums of squares, LRI's normals and
         FITTING's 3x3 inverses (the sixth power of a ring's size) would overflow from about
         1e50 and underflow below 1e-50.
       - Displacements, not positions, are the unknowns: at rest the right-hand side is exactly
         zero, so zero motion reproduces the mesh whatever the conditioning (normal equations
         square it), and a mesh far from the origin loses no digits.
       - Hard constraints by default: the thesis uses soft ones (weight 1), which leave the handle
         short of its target; soft ones are an option and converge to the hard result as w grows.
       - Cotangent weights are clamped at 1e-3 (they go negative where an edge is not locally
         Delaunay): the weights stay positive so the systems stay definite; an intrinsic Delaunay
         retriangulation would be exact but needs an edge-flip pass over the ROI.
       - The thesis fits T_i on absolute coordinates without translation, so its result depends
         on where the origin is; the fit here is on centred coordinates (the centring drops out
         of s and h because sum q_j = 0).
       - The thesis's b2 = b1 x N makes a left-handed frame; here b2 = N x b1. Its normal (3-14)
         misses the wrap-around face and is not normalized; here it is the normalized sum of the
         incident faces' cross products.
       - Each undirected edge is one LRI row (the two directed rows have the same minimizer).
       - LRI's frames are solved as the 9 entries of M_i = F'_i F_i^T on the scalar graph
         Laplacian instead of the thesis's coupled 3n x 3n system: the same minimizer (the rows
         differ by the orthogonal factor F_j), a ninth of the factor and a third of the work.
         When every known rotation is I or one R (a rigid handle), M = I + phi (R - I) with one
         scalar solve for phi, exactly (the problem is linear); other poses take 9 solves.
       - LRI's rotations come from the frames solve alone (M harmonic between the fixed
         frames and the handle's), whatever the handle's positions ask for: when the harmonic
         spread of the turn along the region is not the one the handle's offset implies, the
         positions solve absorbs the mismatch as stretch. With polar frames the positions
         system is exactly the global step of as-rigid-as-possible editing (Sorkine and Alexa
         2007): F'_i c_ij = R_i (x_j - x_i), so the row is x'_j - x'_i = (R_i + R_j) (x_j - x_i)
         / 2. rigid_steps therefore adds that method's local-global steps, started from LRI's
         rotations instead of identities: block descent on the ARAP energy, which keeps rigid
         motions exact and the frame choice irrelevant. The local fit is the iteration
         R <- rot(w) R, w = sum_k R_k x S_k / |sum_k R_k . S_k| over the columns (Mueller et al.
         2016), at most 4 rounds from the previous rotation: no inverse (a flat 1-ring's S has
         rank 2, where Newton's polar iteration fails) and no SVD.
       - The ROI's outside neighbours enter as known values (the thesis leaves this open), and
         only rows that touch an unknown are assembled, so the cost follows the ROI, not the mesh.

   PART 2: SPARSE CHOLESKY
     WHAT
       Compressed sparse column (CSC) matrices; assembly of mesh Laplacians (uniform, cotangent, and
       the thesis's row-normalized one) and of normal equations A^T A + D straight from the square
       adjacency-shaped operator (the rectangular least-squares matrix [L; S] is never formed: its
       constraint rows only add to the diagonal); expansion of a vertex-graph matrix into 3x3-block
       (x, y, z coupled) systems; a sparse Cholesky factorization A = P^T L L^T P with
         - approximate minimum degree ordering (Amestoy, Davis, Duff 1996), written from the paper,
           and, when per-row coordinates are given (vertex positions), nested dissection by
           geometric separators, tried when AMD's fill is high and kept when it gives less fill
           (it does on large meshes),
         - symbolic analysis (elimination tree, postorder, column counts, relaxed supernodes) kept
           apart from the numeric factorization, so a matrix with the same pattern and new values
           (new constraint weights, new cotangent weights) is refactored without a new analysis,
         - a left-looking supernodal numeric factorization with blocked dense kernels of its own
           (no BLAS), solves with several right-hand sides at once, optional iterative refinement,
         - hard constraints by elimination: the free-free block is factored once and each solve
           moves the fixed values to the right-hand side.

     HOW TO USE
         dfm_csc L, A; dfm_chol *chol;
         dfm_mesh_laplacian(positions, nv, indices, nt, DFM_LAPLACIAN_COTAN, NULL, &L);
         dfm_normal_matrix(&L, weights, NULL, &A);          // A = L^T L + diag(weights), lower part
         if (dfm_chol_analyze(&A, NULL, &chol) != DFM_OK) return 1;
         if (dfm_chol_factor(chol, &A) != DFM_OK) return 1; // dfm_chol_get_info: failing column
         dfm_chol_solve(chol, xyz, 3);                       // 3 right-hand sides, column-major, in place
         ... change A's values (same pattern), dfm_chol_factor(chol, &A) again ...
         dfm_chol_free(chol); dfm_csc_free(&A); dfm_csc_free(&L);

     OPTIONS
       Compile time (define before including the implementation):
         DFM_STATIC            all functions are static (DFMDEF = static), for private use in one file
         DFM_MALLOC(sz)        default allocator; define both DFM_MALLOC and DFM_FREE or neither
         DFM_FREE(p)
         DFM_NO_VECTOR_EXTENSIONS  plain C dense kernels instead of GCC/Clang vector types
         DFM_NO_RUNTIME_DISPATCH   never use the AVX / AVX-512 kernels chosen by CPU feature bits
         DFM_NO_AVX512         the AVX kernels at most (same bits either way)
         DFM_TEST_AMD_PIVOT(s, p), DFM_TEST_AMD_STEP(s, p)  test-only hooks into AMD, called before
                               each pivot and after each degree update (tests/test_deform_chol.c
                               audits the degrees through them); undefined: no code
       Run time, dfm_chol_options (zeroed or NULL = defaults; dfm_chol_default_options() resolves):
         ordering       DFM_ORDER_AMD (default), DFM_ORDER_NATURAL, DFM_ORDER_GIVEN (perm below).
         perm           DFM_ORDER_GIVEN: perm[k] = the input row/column eliminated k-th.
         block_size     0 or 1, or b > 1: rows b*i .. b*i+b-1 are one vertex's coupled unknowns
                        (dfm_block_expand); the ordering is computed on the vertex graph (b x smaller)
                        and expanded, which keeps each vertex's unknowns together.
         coords         NULL, or 3 doubles per row (per vertex with block_size b: the positions):
                        when AMD's fill is high, nested dissection is computed too and the
                        ordering with the smaller nnz(L) is kept (see DECISIONS). Checked for
                        NaN/Inf whenever given.
         allocator      NULL = DFM_MALLOC/DFM_FREE; a copy is kept in the factor object.
         progress       NULL, or called with done in [0, 1] during analysis and factorization; a
                        nonzero return cancels (DFM_CANCELLED, nothing leaked). progress_user is passed.

     MATRICES
       dfm_csc holds an n_rows x n_cols matrix column by column: the rows of column j are
       row_index[col_start[j] .. col_start[j+1]-1], with values beside them. The field types:
         size_t   n_rows, n_cols;
         size_t  *col_start;   n_cols + 1 offsets (size_t: nnz may exceed 2^32)
         int32_t *row_index;   col_start[n_cols] row indices (int32_t: at most 2^31 - 1 rows)
         double  *values;      col_start[n_cols] values
         int      kind;        DFM_CSC_GENERAL or DFM_CSC_SYMMETRIC_LOWER
         dfm_allocator allocator;  what dfm_csc_free gives the arrays back to
       kind says what is stored: DFM_CSC_GENERAL (every entry) or DFM_CSC_SYMMETRIC_LOWER (a
       symmetric matrix given by its lower triangle, row >= column; this is what the factorization
       takes). Row indices need not be sorted; duplicate entries are summed. Matrices made by this
       header have sorted rows without duplicates and are freed with dfm_csc_free.

     STRUCTURE
       Analysis: ordering (AMD on the graph of A + A^T without the diagonal; rows denser than
       10 sqrt(n) are ordered last, as AMD does; with coordinates also nested dissection: recursive
       median bisection along the axis whose cut crosses the fewest edges, the smaller side's
       boundary as vertex separator, down to parts of 128 nodes, then minimum degree constrained to
       eliminate the parts first and the separators deepest-first, like CHOLMOD's NESDIS with
       CAMD; tried only when AMD's fill is high, and the smaller fill kept), elimination tree (Liu
       1990) of the permuted matrix, postorder (the tree relabelled, not recomputed), column
       counts (those AMD counted while eliminating when exact, else by row-subtree traversal,
       O(nnz(L))), fundamental supernodes, then relaxed amalgamation (a child merged into its
       parent when the merged block stays small or adds few explicit zeros, as CHOLMOD does), the
       supernode partition, A's entries mapped to their places in L, then each supernode's sorted
       row structure (dfm_chol_analyze calls one function per step, in this order).
       Factor: supernodes in postorder, left-looking: assemble A's columns, subtract the update of
       every descendant supernode that has rows in it (one dense C = L_d L_d'^T
       product per descendant, scattered by relative row indices), then a blocked dense Cholesky of
       the supernode's diagonal block and triangular solve of the rows below it (one blocked
       left-looking pass over the panel: each block of 48 columns is updated, its diagonal block
       factored by columns, and the rows below it solved in tiles of rows held in registers).
       The dense kernels are 4 x 4 register tiles, two-lane vectors through the GCC/Clang vector
       extension (SSE2 / NEON), plain C elsewhere; on x86 CPUs with AVX an 8 x 4 tile compiled for
       AVX, and with AVX-512F a 16 x 4 one, is chosen at run time; the product tiles go over C's
       columns in chunks whose part of B stays in L2 cache. The 3-right-hand-side solve has an
       AVX version too. The vector paths do the same operations in the same order without FMA,
       so they give the same bits (checked: gcc and clang, plain C, SSE2, AVX and AVX-512 builds
       agree on the factor; the plain C solve differs in the last bits). Solve:
       supernodal forward and backward substitution, right-hand sides interleaved four at a time;
       for three right-hand sides each supernode's rows are gathered into a dense block first.

     MEMORY
       The factor object holds the permutation, the supernode row structure (4 bytes a row per
       supernode) and the values of L, one dense column-major block per supernode (8 bytes an
       entry, explicit zeros of the amalgamation included; dfm_chol_info.stored_entries). The
       factorization's workspace is O(n) plus the largest descendant update block, and where the
       AVX-512 kernel is compiled in (x86, GCC/Clang) its packing buffer: 32768 + 20 x (columns
       of the widest supernode) doubles. AMD uses about 2 nnz(A) + 10 n integers during analysis.
       dfm_chol_solve allocates n x min(nrhs, 4) + 4 x (rows of the tallest supernode) doubles per
       call.

     ERRORS
       Every call returns a dfm_result (DFM_OK = 0); dfm_result_string() names it. On failure the
       outputs are zeroed/NULL and nothing is leaked. DFM_ERR_NOT_POSITIVE_DEFINITE: a pivot was
       <= 0 or not finite; dfm_chol_get_info().failed_column is the column in the INPUT numbering.
       DFM_ERR_STRUCTURALLY_SINGULAR: a column has no diagonal entry at all. DFM_ERR_PATTERN_MISMATCH:
       dfm_chol_factor was given a matrix whose pattern differs from the analysed one. Bad input:
       DFM_ERR_INVALID_ARGUMENT (NULL, wrong kind, non-square), DFM_ERR_BAD_INDEX (row out of range,
       or an upper-triangle entry in a lower matrix, or a mesh index >= vertex count),
       DFM_ERR_BAD_VALUE (NaN or infinite value or position, or right-hand side of a solve or
       vector of dfm_csc_multiply), DFM_ERR_TOO_LARGE (sizes that overflow size_t or exceed
       2^31 - 1 rows), DFM_ERR_OUT_OF_MEMORY, DFM_CANCELLED. DFM_ERR_NOT_FINITE: every input was
       finite but a result overflowed (a 1e200 entry squared by dfm_normal_matrix, a product of
       dfm_csc_multiply, or a solution of dfm_chol_solve,
       _solve_refined or dfm_constrained_solve beyond 1e308 because of a tiny pivot); the matrix
       outputs are then freed, and the solves' x holds what was computed (Inf/NaN included).

     THREAD SAFETY
       No global state. A factor object may be used by several threads for dfm_chol_solve at once;
       dfm_chol_factor and dfm_chol_free need exclusive access. Results are deterministic: the same
       input gives the same ordering and the same bits on every run (every tie is broken by a fixed
       rule on the indices). dfm_chol_factor recognises the analysed pattern by its size and a 64-bit
       hash of col_start and row_index.

     PRECISION
       Double precision throughout. Backward stable for SPD matrices; the relative residual
       |b - Ax|inf / (|A|inf |x|inf + |b|inf) is around 1e-16 x growth. Normal equations square
       the condition number (the bi-Laplacian): use dfm_chol_solve_refined there if needed.

     LIMITS
       At most 2^31 - 1 rows; nnz(L) limited only by size_t and memory. Nested dissection needs
       coordinates (no graph partitioner); its separators are planar cuts, not refined (no
       Fiduccia-Mattheyses), so it reaches METIS's fill only within about 10% on meshes. Single
       threaded; the dense kernels use no FMA (one rounding for the product, one for the sum, on
       every path), so their peak is half that of an FMA BLAS of the same width.
       The bits do not depend on the compiler's FMA contraction (GCC in any dialect, C or C++, with
       any -ffp-contract; clang at its default): the implementation turns contraction off for its
       own code and restores the user's setting after it. Clang's -ffp-contract=fast ignores that
       pragma: there every factor's and solve's last bits differ (still the same on every run).

     DECISIONS
       - The ordering is AMD as in the 1996 paper (ties broken as in the authors' reference code:
         among equal degrees the most recently inserted variable, initially the highest index; this
         gave 15% less fill than the opposite order on the 1M-triangle sphere and reproduces
         CHOLMOD's AMD fill on the bunny to within 60 entries): quotient graph, approximate
         external degree bound d_i = min(n - k, d_i + |Lp \ i|, |Ai \ i| + |Lp \ i| + sum |Le \ Lp|), element
         absorption (also aggressive absorption of elements with |Le \ Lp| = 0), supervariables by
         hashing, mass elimination. Dense rows are removed first and ordered last.
       - Nested dissection is tried only when AMD's fill is high, by CHOLMOD's test for trying
         METIS (nnz(L) >= 5 nnz(A) and sum of squared column counts >= 500 nnz(L)): on small and
         medium meshes AMD wins anyway and dissection would more than double the analysis. The
         fills compared are the ones AMD and its constrained form count while eliminating
         (exact when no dense row is set aside; otherwise both orderings are counted
         symbolically), so no extra symbolic pass is made.
       - Column counts come from the minimum degree ordering itself: the element formed at a
         pivot is exactly the pivot's column below its supervariable, so AMD (and its constrained
         form in nested dissection) knows every count without a symbolic pass when no dense row
         was set aside. Otherwise (given or natural orderings, dense rows, vertex blocks) they
         are counted by row subtrees rather than Gilbert-Ng-Peyton: O(nnz(L)) instead of almost
         O(nnz(A)), simpler.
       - Relaxed amalgamation uses CHOLMOD's published thresholds (merge when the result has at most
         4 columns, or at most 16 columns and < 80% zeros, or 48 and < 10%, else < 5%), but merges
         a supernode only into the one starting right after it when that one is its parent.
         CHOLMOD also merges into a parent already absorbed by the next group; that gives its
         supernode counts (about 40% of ours on mesh systems) but 14% more stored entries, and
         with these kernels it was not faster.
       - No FMA in the dense kernels: every path (plain C, SSE2/NEON, AVX, AVX-512) rounds the
         product and the sum separately, so all give the same bits; with FMA the portable paths
         would need C99 fma() per operation, a slow library call on CPUs without FMA. The price
         is half the peak of an FMA kernel of the same width (see LIMITS).

   REFERENCES
     P. Amestoy, T. Davis, I. Duff, "An approximate minimum degree ordering algorithm",
       SIAM J. Matrix Anal. Appl. 17(4), 1996.
     J. W. H. Liu, "The role of elimination trees in sparse factorization", SIAM J. Matrix Anal.
       Appl. 11(1), 1990.
     E. Ng, B. Peyton, "Block sparse Cholesky algorithms on advanced uniprocessor computers",
       SIAM J. Sci. Comput. 14(5), 1993 (left-looking supernodal factorization).
     C. Ashcraft, R. Grimes, "The influence of relaxed supernode partitions on the multifrontal
       method", ACM TOMS 15(4), 1989.
     T. Davis, "Direct Methods for Sparse Linear Systems", SIAM 2006.
     Y. Chen, T. Davis, W. Hager, S. Rajamanickam, "CHOLMOD", ACM TOMS 35(3), 2008.
     A. George, "Nested dissection of a regular finite element mesh", SIAM J. Numer. Anal. 10,
       1973.
     M. Meyer, M. Desbrun, P. Schroeder, A. Barr, "Discrete differential-geometry operators for
       triangulated 2-manifolds", VisMath 2002 (cotangent weights). */
#ifndef DFM_DEFORM_H
#define DFM_DEFORM_H

#include <stddef.h>
#include <stdint.h>

#ifdef DFM_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define DFMDEF static __attribute__((unused))
#else
#define DFMDEF static
#endif
#else
#define DFMDEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum dfm_result {
    DFM_OK = 0,
    DFM_ERR_INVALID_ARGUMENT,      /* NULL where data is needed, wrong matrix kind, not square */
    DFM_ERR_BAD_INDEX,             /* row index out of range or above the diagonal; mesh index */
    DFM_ERR_BAD_VALUE,             /* NaN or infinite value or position */
    DFM_ERR_NOT_POSITIVE_DEFINITE, /* a pivot <= 0: see dfm_chol_info.failed_column */
    DFM_ERR_STRUCTURALLY_SINGULAR, /* a column without a diagonal entry */
    DFM_ERR_PATTERN_MISMATCH,      /* refactorization with a pattern other than the analysed one */
    DFM_ERR_TOO_LARGE,             /* sizes overflow size_t, or more than 2^31 - 1 rows */
    DFM_ERR_OUT_OF_MEMORY,         /* the allocator returned NULL */
    DFM_CANCELLED,                 /* the progress callback returned nonzero */
    DFM_ERR_EMPTY_ROI,             /* no vertex of the ROI may move (all are handle, or none) */
    DFM_ERR_HANDLE_OUTSIDE_ROI,    /* a handle vertex is not in the ROI */
    DFM_ERR_UNCONSTRAINED,         /* a connected part of the ROI touches no fixed or handle vertex */
    DFM_ERR_DEGENERATE_TRIANGLE,   /* a zero-area triangle (or repeated index) touches the ROI */
    DFM_ERR_NON_MANIFOLD,          /* an edge shared by more than two triangles */
    DFM_ERR_UNWELDED,              /* two used vertices at the same position (a triangle soup) */
    DFM_ERR_NOT_FINITE             /* finite input, but a result overflowed to Inf or NaN */
} dfm_result;

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct dfm_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} dfm_allocator;

/* ---- sparse matrices ------------------------------------------------------------------------- */

enum { DFM_CSC_GENERAL = 0, DFM_CSC_SYMMETRIC_LOWER = 1 };

typedef struct dfm_csc {
    size_t n_rows, n_cols;
    size_t *col_start;  /* n_cols + 1 */
    int32_t *row_index; /* col_start[n_cols] */
    double *values;     /* col_start[n_cols] */
    int kind;           /* DFM_CSC_GENERAL or DFM_CSC_SYMMETRIC_LOWER */
    dfm_allocator allocator; /* what dfm_csc_free uses (matrices made by this header) */
} dfm_csc;

enum { DFM_LAPLACIAN_UNIFORM = 0, DFM_LAPLACIAN_COTAN = 1, DFM_LAPLACIAN_UNIFORM_NORMALIZED = 2 };

/* Allocates an n_rows x n_cols matrix with room for nnz entries (col_start zeroed). */
DFMDEF dfm_result dfm_csc_alloc(size_t n_rows, size_t n_cols, size_t nnz, int kind,
                                const dfm_allocator *allocator, dfm_csc *out);

/* Frees a matrix made by this header (zeroes the struct). NULL or a zeroed struct is allowed. */
DFMDEF void dfm_csc_free(dfm_csc *m);

/* Checks a matrix: pointers, sizes, row indices in range (and >= column for SYMMETRIC_LOWER),
   finite values. Returns DFM_OK or the code the other calls would return. */
DFMDEF dfm_result dfm_csc_validate(const dfm_csc *m);

/* y = A x for nrhs vectors (column-major, leading dimensions n_cols for x and n_rows for y).
   A symmetric-lower matrix is applied as the full symmetric matrix. */
DFMDEF dfm_result dfm_csc_multiply(const dfm_csc *a, const double *x, double *y, size_t nrhs);

/* The Laplacian of a triangle mesh (positions: 3 floats a vertex; indices: 3 a triangle).
   UNIFORM: L = D - W with w_ij = 1 per edge (symmetric, positive semidefinite), lower stored.
   COTAN:   w_ij = (cot a_ij + cot b_ij) / 2 over the angles opposite edge ij, diagonal = sum;
            angles of degenerate triangles count 0. Symmetric, lower stored.
   UNIFORM_NORMALIZED: the thesis's L = I - D^-1 W (row i: 1, -1/d_i), not symmetric, GENERAL.
   Vertices in no triangle get a zero row (and, for the symmetric kinds, a zero diagonal entry
   stored, so the pattern is complete). */
DFMDEF dfm_result dfm_mesh_laplacian(const float *positions, size_t vertex_count, const uint32_t *indices,
                                     size_t triangle_count, int kind, const dfm_allocator *allocator,
                                     dfm_csc *out);

/* The normal-equation matrix M = A^T A + diag(diagonal), lower triangle (SYMMETRIC_LOWER), for a
   square or rectangular A (GENERAL) or a symmetric A (SYMMETRIC_LOWER: M = A^2 + diag). diagonal
   may be NULL (zero); it is where the constraint rows of the least-squares system go: a soft
   constraint of weight w on unknown i adds w^2 to diagonal[i]. Every diagonal entry is stored. */
DFMDEF dfm_result dfm_normal_matrix(const dfm_csc *a, const double *diagonal, const dfm_allocator *allocator,
                                    dfm_csc *out);

/* Expands a symmetric-lower n x n matrix into a (b n) x (b n) symmetric-lower one, entry (i, j)
   becoming the b x b block blocks[k*b*b + r*b + c] (row r, column c of the block) for the k-th
   stored entry of g; blocks == NULL means value * identity. Diagonal blocks must be symmetric
   (their upper part is ignored). Row b*i + r of the result is unknown r of vertex i. */
DFMDEF dfm_result dfm_block_expand(const dfm_csc *g, size_t b, const double *blocks,
                                   const dfm_allocator *allocator, dfm_csc *out);

/* ---- sparse Cholesky --------------------------------------------------------------------------- */

enum { DFM_ORDER_AMD = 0, DFM_ORDER_NATURAL = 1, DFM_ORDER_GIVEN = 2 };

typedef struct dfm_chol_options {
    int ordering;                 /* DFM_ORDER_AMD (0), DFM_ORDER_NATURAL or DFM_ORDER_GIVEN */
    const int32_t *perm;          /* DFM_ORDER_GIVEN: a permutation of 0..n-1 */
    size_t block_size;            /* 0/1, or b: order the graph of b x b vertex blocks */
    const double *coords;         /* NULL, or 3 per row (per vertex with block_size b): nested
                                     dissection is tried too when AMD's fill is high, and the
                                     smaller fill kept */
    const dfm_allocator *allocator;
    int (*progress)(void *user, float done);
    void *progress_user;
} dfm_chol_options;

typedef struct dfm_chol dfm_chol; /* opaque: analysis + factor */

typedef struct dfm_chol_info {
    size_t n;
    size_t nnz_l;          /* entries of L (diagonal included), exact symbolic count */
    size_t stored_entries; /* entries held, amalgamation zeros included */
    size_t supernodes;
    double flops;          /* of the numeric factorization, sum over columns of count^2 */
    int factored;          /* 1 after a successful dfm_chol_factor */
    long long failed_column; /* input numbering of the failing pivot, -1 if none */
} dfm_chol_info;

DFMDEF dfm_chol_options dfm_chol_default_options(void);

/* Ordering and symbolic analysis of a SYMMETRIC_LOWER matrix (only its pattern is read). */
DFMDEF dfm_result dfm_chol_analyze(const dfm_csc *a, const dfm_chol_options *options, dfm_chol **out);

/* Numeric factorization of a matrix with the analysed pattern (values may change between calls).
   On DFM_ERR_NOT_POSITIVE_DEFINITE the object stays usable for another dfm_chol_factor. */
DFMDEF dfm_result dfm_chol_factor(dfm_chol *chol, const dfm_csc *a);

/* Solves A X = B in place: x holds n x nrhs values column-major (column q at x + q*n). */
DFMDEF dfm_result dfm_chol_solve(const dfm_chol *chol, double *x, size_t nrhs);

/* x = A^-1 b with up to max_steps steps of iterative refinement x += A^-1 (b - A x), stopping when
   the residual stops shrinking. a is the factored matrix; b and x are n x nrhs (may not alias). */
DFMDEF dfm_result dfm_chol_solve_refined(const dfm_chol *chol, const dfm_csc *a, const double *b, double *x,
                                         size_t nrhs, int max_steps);

/* The permutation used: perm[k] = input index eliminated k-th (n entries). */
DFMDEF const int32_t *dfm_chol_permutation(const dfm_chol *chol);

/* Entries of each column of L, diagonal included (n entries; column k is input column perm[k]). */
DFMDEF const size_t *dfm_chol_column_counts(const dfm_chol *chol);

DFMDEF void dfm_chol_get_info(const dfm_chol *chol, dfm_chol_info *info);

DFMDEF void dfm_chol_free(dfm_chol *chol);

/* ---- hard constraints by elimination ------------------------------------------------------- */

typedef struct dfm_constrained dfm_constrained; /* opaque */

/* Analyses the free-free block of a SYMMETRIC_LOWER A: fixed[i] != 0 marks unknown i as fixed.
   At least one unknown must be free. options as for dfm_chol_analyze, with coords (3 per row of
   A) if given; block_size and DFM_ORDER_GIVEN refer to the full system and are replaced by
   plain AMD on the free block. */
DFMDEF dfm_result dfm_constrained_analyze(const dfm_csc *a, const unsigned char *fixed,
                                          const dfm_chol_options *options, dfm_constrained **out);

/* Factors the free-free block of a (same pattern as analysed). */
DFMDEF dfm_result dfm_constrained_factor(dfm_constrained *c, const dfm_csc *a);

/* Solves A x = b for the free unknowns with x fixed to fixed_values at the fixed ones:
   x_f = A_ff^-1 (b_f - A_fc x_c). b, fixed_values (read only at fixed rows) and x are n x nrhs
   column-major; x may alias fixed_values but not b. */
DFMDEF dfm_result dfm_constrained_solve(const dfm_constrained *c, const double *b, const double *fixed_values,
                                        double *x, size_t nrhs);

/* The factor of the free-free block (for its info), NULL before analysis. */
DFMDEF const dfm_chol *dfm_constrained_chol(const dfm_constrained *c);

DFMDEF void dfm_constrained_free(dfm_constrained *c);

/* ---- deformation (part 2): Laplacian, transformation fitting, LRI ---------------------------- */

enum { DFM_METHOD_LAPLACIAN = 0, DFM_METHOD_FITTING = 1, DFM_METHOD_LRI = 2 };
enum { DFM_WEIGHTS_UNIFORM = 0, DFM_WEIGHTS_COTAN = 1 };
enum { DFM_HANDLE_HARD = 0, DFM_HANDLE_SOFT = 1 };
enum { DFM_FRAMES_FIRST_EDGE = 0, DFM_FRAMES_MAX_ELEVATION = 1 };
enum { DFM_ORTHO_NONE = 0, DFM_ORTHO_POLAR = 1, DFM_ORTHO_GRAM_SCHMIDT = 2 };

typedef struct dfm_deform_options {
    int method;            /* DFM_METHOD_LAPLACIAN (0), DFM_METHOD_FITTING or DFM_METHOD_LRI */
    int weights;           /* DFM_WEIGHTS_UNIFORM (0, the thesis's) or DFM_WEIGHTS_COTAN */
    int handle_constraint; /* DFM_HANDLE_HARD (0: eliminated) or DFM_HANDLE_SOFT (weighted rows) */
    double handle_weight;  /* soft constraints: the weight w of the handle rows (0 = 1) */
    int frames;            /* LRI: DFM_FRAMES_FIRST_EDGE (0) or DFM_FRAMES_MAX_ELEVATION (ch. 4) */
    int orthonormalize;    /* LRI: DFM_ORTHO_NONE (0), DFM_ORTHO_POLAR, DFM_ORTHO_GRAM_SCHMIDT */
    int refine_steps;      /* iterative refinement steps per solve (0 = none) */
    int rigid_steps;       /* LRI: local-global (as-rigid-as-possible) steps after the solve (0) */
    const dfm_allocator *allocator;
    int (*progress)(void *user, float done);
    void *progress_user;
} dfm_deform_options;

typedef struct dfm_deform dfm_deform; /* opaque: the factored systems of one ROI and handle */

typedef struct dfm_deform_info {
    size_t n_free;       /* ROI vertices that are not handle vertices */
    size_t n_unknown;    /* vertices solved for (free, plus handle with soft constraints) */
    size_t nnz_l;        /* entries of the factors (all systems) */
    size_t bytes;        /* memory held by the object */
} dfm_deform_info;

DFMDEF dfm_deform_options dfm_deform_default_options(void);

/* Builds and factors the systems for one ROI and handle. positions: 3 doubles a vertex; indices:
   3 a triangle. roi[v] != 0: v may move; handle[v] != 0: v is moved by the caller (must be in the
   ROI); every vertex outside the ROI is fixed. */
DFMDEF dfm_result dfm_deform_setup(const double *positions, size_t vertex_count, const uint32_t *indices,
                                   size_t triangle_count, const unsigned char *roi, const unsigned char *handle,
                                   const dfm_deform_options *options, dfm_deform **out);

/* One frame. targets: 3 doubles a vertex, read at the handle and fixed vertices (a copy of the
   positions with the handle moved, see dfm_pose_*). rotations: NULL (identity), or 9 doubles a
   vertex (row-major), read at the handle and fixed vertices: LRI's frame targets (R times the
   original frame). out: 3 doubles a vertex, every vertex written (may alias targets). */
DFMDEF dfm_result dfm_deform_solve(dfm_deform *d, const double *targets, const double *rotations, double *out);

DFMDEF void dfm_deform_get_info(const dfm_deform *d, dfm_deform_info *info);
DFMDEF void dfm_deform_free(dfm_deform *d);

/* ---- ROI and pose helpers ------------------------------------------------------------------------ */

/* Grows mask (nonzero = member) by k rings of mesh neighbours. */
DFMDEF dfm_result dfm_roi_rings(const uint32_t *indices, size_t triangle_count, size_t vertex_count, unsigned k,
                                unsigned char *mask, const dfm_allocator *allocator);

/* mask[v] = 1 where the shortest path along mesh edges from a seed (seeds[v] != 0) is <= radius,
   else 0 (the edge-path distance approximates the geodesic one from above). */
DFMDEF dfm_result dfm_roi_geodesic(const double *positions, size_t vertex_count, const uint32_t *indices,
                                   size_t triangle_count, const unsigned char *seeds, double radius,
                                   unsigned char *mask, const dfm_allocator *allocator);

/* The welding pre-pass for triangle soups: remap[v] = the lowest-numbered vertex at exactly the
   same position as v (vertex_count entries), out_indices = indices through remap (3 a triangle;
   may alias indices). Set up on out_indices; afterwards out[v] = out[remap[v]] moves the copies. */
DFMDEF dfm_result dfm_weld(const double *positions, size_t vertex_count, const uint32_t *indices,
                           size_t triangle_count, uint32_t *remap, uint32_t *out_indices,
                           const dfm_allocator *allocator);

/* R (row-major 3x3) = rotation by angle (radians, right hand) about axis (any length > 0). */
DFMDEF void dfm_rotation(const double axis[3], double angle, double R[9]);

/* targets = positions (3 per vertex) and rotations = identity (9 per vertex; may be NULL). */
DFMDEF void dfm_pose_identity(const double *positions, size_t vertex_count, double *targets, double *rotations);

/* For mask[v] != 0: targets[v] = R (positions[v] - center) + center + t, rotations[v] = R. R NULL
   means identity (a translation), t NULL means zero; rotations may be NULL. */
DFMDEF void dfm_pose_rigid(const double *positions, size_t vertex_count, const unsigned char *mask,
                           const double R[9], const double center[3], const double t[3], double *targets,
                           double *rotations);

/* Twist: rotation by angle about the line through point along axis. */
DFMDEF void dfm_pose_twist(const double *positions, size_t vertex_count, const unsigned char *mask,
                           const double point[3], const double axis[3], double angle, double *targets,
                           double *rotations);

/* Bend: the part of a bar from base along axis, of length len, bent by angle towards toward
   (made perpendicular to axis) into a circular arc of the same length: the handle moves rigidly,
   turned by angle, so that the point base + len axis lands at the end of the arc. */
DFMDEF void dfm_pose_bend(const double *positions, size_t vertex_count, const unsigned char *mask,
                          const double base[3], const double axis[3], const double toward[3], double len,
                          double angle, double *targets, double *rotations);

/* "DFM_OK", "DFM_ERR_BAD_INDEX", ... (the enum name); "DFM_ERR_?" outside the enum. */
DFMDEF const char *dfm_result_string(dfm_result r);

#ifdef __cplusplus
}
#endif
#endif /* DFM_DEFORM_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef DFM_IMPLEMENTATION
#ifndef DFM_IMPLEMENTATION_DONE
#define DFM_IMPLEMENTATION_DONE

#include <string.h>
#include <math.h>

#if defined(DFM_MALLOC) && defined(DFM_FREE)
/* both given */
#elif !defined(DFM_MALLOC) && !defined(DFM_FREE)
#include <stdlib.h>
#define DFM_MALLOC(sz) malloc(sz)
#define DFM_FREE(p) free(p)
#else
#error "deform.h: define both DFM_MALLOC and DFM_FREE, or neither"
#endif

/* FMA contraction off from here to the end of the implementation, the user's setting restored
   after it: each a * b + c rounds twice whatever the dialect or -ffp-contract, so the bits do not
   depend on them (see LIMITS). GCC ignores STDC FP_CONTRACT but honours its optimize pragma; clang
   takes fp contract inside float_control push/pop (except under -ffp-contract=fast, which ignores
   pragmas); other compilers: nothing. */
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(push)
#pragma clang fp contract(off)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------------------------------
   Section: results and allocation
   --------------------------------------------------------------------------------------------- */

DFMDEF const char *dfm_result_string(dfm_result r)
{
    switch (r) {
    case DFM_OK: return "DFM_OK";
    case DFM_ERR_INVALID_ARGUMENT: return "DFM_ERR_INVALID_ARGUMENT";
    case DFM_ERR_BAD_INDEX: return "DFM_ERR_BAD_INDEX";
    case DFM_ERR_BAD_VALUE: return "DFM_ERR_BAD_VALUE";
    case DFM_ERR_NOT_POSITIVE_DEFINITE: return "DFM_ERR_NOT_POSITIVE_DEFINITE";
    case DFM_ERR_STRUCTURALLY_SINGULAR: return "DFM_ERR_STRUCTURALLY_SINGULAR";
    case DFM_ERR_PATTERN_MISMATCH: return "DFM_ERR_PATTERN_MISMATCH";
    case DFM_ERR_TOO_LARGE: return "DFM_ERR_TOO_LARGE";
    case DFM_ERR_OUT_OF_MEMORY: return "DFM_ERR_OUT_OF_MEMORY";
    case DFM_CANCELLED: return "DFM_CANCELLED";
    case DFM_ERR_EMPTY_ROI: return "DFM_ERR_EMPTY_ROI";
    case DFM_ERR_HANDLE_OUTSIDE_ROI: return "DFM_ERR_HANDLE_OUTSIDE_ROI";
    case DFM_ERR_UNCONSTRAINED: return "DFM_ERR_UNCONSTRAINED";
    case DFM_ERR_DEGENERATE_TRIANGLE: return "DFM_ERR_DEGENERATE_TRIANGLE";
    case DFM_ERR_NON_MANIFOLD: return "DFM_ERR_NON_MANIFOLD";
    case DFM_ERR_UNWELDED: return "DFM_ERR_UNWELDED";
    case DFM_ERR_NOT_FINITE: return "DFM_ERR_NOT_FINITE";
    }
    return "DFM_ERR_?";
}

static void *dfm__default_alloc(void *user, size_t size) { (void)user; return DFM_MALLOC(size); }
static void dfm__default_free(void *user, void *ptr) { (void)user; DFM_FREE(ptr); }

static dfm_allocator dfm__resolve_allocator(const dfm_allocator *a)
{
    dfm_allocator r;
    if (a && a->alloc && a->free) return *a;
    r.alloc = dfm__default_alloc;
    r.free = dfm__default_free;
    r.user = NULL;
    return r;
}

#define DFM__MAX_N ((size_t)0x7ffffffe)

/* count * size bytes (at least 1), or NULL; *err says why (TOO_LARGE or OUT_OF_MEMORY) */
static void *dfm__alloc(const dfm_allocator *a, size_t count, size_t size, dfm_result *err)
{
    void *p;
    if (size != 0 && count > ((size_t)-1 >> 1) / size) {
        if (*err == DFM_OK) *err = DFM_ERR_TOO_LARGE;
        return NULL;
    }
    p = a->alloc(a->user, count * size > 0 ? count * size : 1);
    if (!p && *err == DFM_OK) *err = DFM_ERR_OUT_OF_MEMORY;
    return p;
}

static void dfm__free(const dfm_allocator *a, void *p)
{
    if (p) a->free(a->user, p);
}

static int dfm__finite(double x) { return x - x == 0.0; }

/* 1 when every one of the n values is finite */
static int dfm__all_finite(const double *x, size_t n)
{
    double s = 0.0;
    size_t i;
    for (i = 0; i < n; i++) s += x[i] - x[i]; /* 0 unless some x[i] is Inf or NaN */
    return s == 0.0;
}

/* ---------------------------------------------------------------------------------------------
   Section: CSC basics
   --------------------------------------------------------------------------------------------- */

DFMDEF dfm_result dfm_csc_alloc(size_t n_rows, size_t n_cols, size_t nnz, int kind,
                                const dfm_allocator *allocator, dfm_csc *out)
{
    dfm_result err = DFM_OK;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (kind != DFM_CSC_GENERAL && kind != DFM_CSC_SYMMETRIC_LOWER) return DFM_ERR_INVALID_ARGUMENT;
    if (kind == DFM_CSC_SYMMETRIC_LOWER && n_rows != n_cols) return DFM_ERR_INVALID_ARGUMENT;
    if (n_rows > DFM__MAX_N || n_cols > DFM__MAX_N) return DFM_ERR_TOO_LARGE;
    out->allocator = dfm__resolve_allocator(allocator);
    out->col_start = (size_t *)dfm__alloc(&out->allocator, n_cols + 1, sizeof(size_t), &err);
    out->row_index = (int32_t *)dfm__alloc(&out->allocator, nnz, sizeof(int32_t), &err);
    out->values = (double *)dfm__alloc(&out->allocator, nnz, sizeof(double), &err);
    if (err != DFM_OK) {
        dfm_csc_free(out);
        return err;
    }
    memset(out->col_start, 0, (n_cols + 1) * sizeof(size_t));
    out->n_rows = n_rows;
    out->n_cols = n_cols;
    out->kind = kind;
    return DFM_OK;
}

DFMDEF void dfm_csc_free(dfm_csc *m)
{
    if (!m) return;
    if (m->allocator.free) {
        dfm__free(&m->allocator, m->col_start);
        dfm__free(&m->allocator, m->row_index);
        dfm__free(&m->allocator, m->values);
    }
    memset(m, 0, sizeof *m);
}

static dfm_result dfm__validate_pattern(const dfm_csc *m)
{
    size_t j, p;
    if (!m || !m->col_start) return DFM_ERR_INVALID_ARGUMENT;
    if (m->kind != DFM_CSC_GENERAL && m->kind != DFM_CSC_SYMMETRIC_LOWER) return DFM_ERR_INVALID_ARGUMENT;
    if (m->kind == DFM_CSC_SYMMETRIC_LOWER && m->n_rows != m->n_cols) return DFM_ERR_INVALID_ARGUMENT;
    if (m->n_rows > DFM__MAX_N || m->n_cols > DFM__MAX_N) return DFM_ERR_TOO_LARGE;
    if (m->col_start[0] != 0) return DFM_ERR_INVALID_ARGUMENT;
    for (j = 0; j < m->n_cols; j++)
        if (m->col_start[j + 1] < m->col_start[j]) return DFM_ERR_INVALID_ARGUMENT;
    if (m->col_start[m->n_cols] > 0 && !m->row_index) return DFM_ERR_INVALID_ARGUMENT;
    for (j = 0; j < m->n_cols; j++)
        for (p = m->col_start[j]; p < m->col_start[j + 1]; p++) {
            int32_t i = m->row_index[p];
            if (i < 0 || (size_t)i >= m->n_rows) return DFM_ERR_BAD_INDEX;
            if (m->kind == DFM_CSC_SYMMETRIC_LOWER && (size_t)i < j) return DFM_ERR_BAD_INDEX;
        }
    return DFM_OK;
}

static dfm_result dfm__validate_values(const dfm_csc *m)
{
    size_t p, nnz = m->col_start[m->n_cols];
    if (nnz > 0 && !m->values) return DFM_ERR_INVALID_ARGUMENT;
    for (p = 0; p < nnz; p++)
        if (!dfm__finite(m->values[p])) return DFM_ERR_BAD_VALUE;
    return DFM_OK;
}

DFMDEF dfm_result dfm_csc_validate(const dfm_csc *m)
{
    dfm_result r = dfm__validate_pattern(m);
    return r != DFM_OK ? r : dfm__validate_values(m);
}

DFMDEF dfm_result dfm_csc_multiply(const dfm_csc *a, const double *x, double *y, size_t nrhs)
{
    size_t j, p, q, nr, nc;
    dfm_result r = dfm_csc_validate(a);
    if (r != DFM_OK) return r;
    if ((!x || !y) && nrhs > 0) return DFM_ERR_INVALID_ARGUMENT;
    nr = a->n_rows;
    nc = a->n_cols;
    if (nrhs > 0 && (nc > ((size_t)-1 >> 4) / nrhs || nr > ((size_t)-1 >> 4) / nrhs)) return DFM_ERR_TOO_LARGE;
    if (!dfm__all_finite(x, nc * nrhs)) return DFM_ERR_BAD_VALUE;
    for (q = 0; q < nrhs; q++) {
        const double *xq = x + q * nc;
        double *yq = y + q * nr;
        memset(yq, 0, nr * sizeof(double));
        for (j = 0; j < nc; j++)
            for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
                size_t i = (size_t)a->row_index[p];
                yq[i] += a->values[p] * xq[j];
                if (a->kind == DFM_CSC_SYMMETRIC_LOWER && i != j) yq[j] += a->values[p] * xq[i];
            }
    }
    return dfm__all_finite(y, nr * nrhs) ? DFM_OK : DFM_ERR_NOT_FINITE;
}

/* Builds a CSC matrix from triplets (row, col, value), summing duplicates, rows sorted. */
static dfm_result dfm__from_triplets(size_t nr, size_t nc, size_t count, const int32_t *ti, const int32_t *tj,
                                     const double *tv, int kind, const dfm_allocator *al, dfm_csc *out)
{
    dfm_result err = DFM_OK;
    size_t *rcount = NULL, *ccount = NULL, k, j, p, q;
    int32_t *ri = NULL, *rj = NULL;
    double *rv = NULL;
    memset(out, 0, sizeof *out);
    /* bucket by row, then stably by column: each column's entries come out sorted by row */
    rcount = (size_t *)dfm__alloc(al, nr + 1, sizeof(size_t), &err);
    ccount = (size_t *)dfm__alloc(al, nc + 1, sizeof(size_t), &err);
    ri = (int32_t *)dfm__alloc(al, count, sizeof(int32_t), &err);
    rj = (int32_t *)dfm__alloc(al, count, sizeof(int32_t), &err);
    rv = (double *)dfm__alloc(al, count, sizeof(double), &err);
    if (err != DFM_OK) goto done;
    memset(rcount, 0, (nr + 1) * sizeof(size_t));
    for (k = 0; k < count; k++) rcount[ti[k] + 1]++;
    for (k = 0; k < nr; k++) rcount[k + 1] += rcount[k];
    for (k = 0; k < count; k++) {
        p = rcount[ti[k]]++;
        ri[p] = ti[k];
        rj[p] = tj[k];
        rv[p] = tv[k];
    }
    /* counts per column of the distinct entries */
    memset(ccount, 0, (nc + 1) * sizeof(size_t));
    for (k = 0; k < count; k++) ccount[rj[k] + 1]++;
    for (k = 0; k < nc; k++) ccount[k + 1] += ccount[k];
    err = dfm_csc_alloc(nr, nc, count, kind, al, out);
    if (err != DFM_OK) goto done;
    for (k = 0; k < count; k++) {
        p = ccount[rj[k]]++;
        out->row_index[p] = ri[k];
        out->values[p] = rv[k];
    }
    /* ccount[j] is now the end of column j; merge duplicates in place */
    q = 0;
    {
        size_t start = 0;
        for (j = 0; j < nc; j++) {
            size_t end = ccount[j], first = q;
            for (p = start; p < end; p++) {
                int32_t i = out->row_index[p];
                if (q > first && out->row_index[q - 1] == i) {
                    out->values[q - 1] += out->values[p];
                } else {
                    out->row_index[q] = i;
                    out->values[q] = out->values[p];
                    q++;
                }
            }
            out->col_start[j] = first;
            start = end;
        }
        out->col_start[nc] = q;
    }
done:
    dfm__free(al, rcount);
    dfm__free(al, ccount);
    dfm__free(al, ri);
    dfm__free(al, rj);
    dfm__free(al, rv);
    if (err != DFM_OK) dfm_csc_free(out);
    return err;
}

/* ---------------------------------------------------------------------------------------------
   Section: mesh Laplacians
   --------------------------------------------------------------------------------------------- */

static void dfm__sub3(const double *a, const double *b, double *r)
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}
static double dfm__dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void dfm__cross3(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

/* cot of the angle at o in triangle (o, a, b); 0 for a degenerate corner */
static double dfm__cot_d(const double *o, const double *a, const double *b)
{
    double u[3], v[3], c[3], d, s;
    dfm__sub3(a, o, u);
    dfm__sub3(b, o, v);
    dfm__cross3(u, v, c);
    d = dfm__dot3(u, v);
    s = sqrt(dfm__dot3(c, c));
    if (!(s > 1e-12 * sqrt(dfm__dot3(u, u) * dfm__dot3(v, v)))) return 0.0;
    return d / s;
}

static double dfm__cot(const float *o, const float *a, const float *b)
{
    double od[3], ad[3], bd[3];
    int k;
    for (k = 0; k < 3; k++) {
        od[k] = o[k];
        ad[k] = a[k];
        bd[k] = b[k];
    }
    return dfm__cot_d(od, ad, bd);
}

DFMDEF dfm_result dfm_mesh_laplacian(const float *positions, size_t vertex_count, const uint32_t *indices,
                                     size_t triangle_count, int kind, const dfm_allocator *allocator,
                                     dfm_csc *out)
{
    dfm_allocator al = dfm__resolve_allocator(allocator);
    dfm_result err = DFM_OK;
    int32_t *ti = NULL, *tj = NULL;
    double *tv = NULL;
    size_t t, k, count = 0, cap, n = vertex_count;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (kind < DFM_LAPLACIAN_UNIFORM || kind > DFM_LAPLACIAN_UNIFORM_NORMALIZED) return DFM_ERR_INVALID_ARGUMENT;
    if ((triangle_count > 0 && (!indices || !positions)) || vertex_count == 0) return DFM_ERR_INVALID_ARGUMENT;
    if (vertex_count > DFM__MAX_N) return DFM_ERR_TOO_LARGE;
    if (triangle_count > ((size_t)-1 >> 4) / 6) return DFM_ERR_TOO_LARGE;
    for (t = 0; t < 3 * triangle_count; t++)
        if (indices[t] >= vertex_count) return DFM_ERR_BAD_INDEX;
    for (t = 0; t < 3 * triangle_count; t++)
        for (k = 0; k < 3; k++)
            if (!dfm__finite((double)positions[3 * (size_t)indices[t] + k])) return DFM_ERR_BAD_VALUE;
    /* triplets: per triangle edge both (i,j) and (j,i) for GENERAL, (max,min) for lower; plus
       diagonal entries */
    cap = 6 * triangle_count + n;
    ti = (int32_t *)dfm__alloc(&al, cap, sizeof(int32_t), &err);
    tj = (int32_t *)dfm__alloc(&al, cap, sizeof(int32_t), &err);
    tv = (double *)dfm__alloc(&al, cap, sizeof(double), &err);
    if (err != DFM_OK) goto done;
    for (t = 0; t < triangle_count; t++) {
        const uint32_t *f = indices + 3 * t;
        for (k = 0; k < 3; k++) {
            uint32_t a = f[k], b = f[(k + 1) % 3], o = f[(k + 2) % 3];
            double w = 1.0;
            if (a == b) continue;
            if (kind == DFM_LAPLACIAN_COTAN)
                w = 0.5 * dfm__cot(positions + 3 * (size_t)o, positions + 3 * (size_t)a, positions + 3 * (size_t)b);
            if (kind == DFM_LAPLACIAN_UNIFORM_NORMALIZED) {
                ti[count] = (int32_t)a; tj[count] = (int32_t)b; tv[count++] = 1.0;
                ti[count] = (int32_t)b; tj[count] = (int32_t)a; tv[count++] = 1.0;
            } else {
                ti[count] = (int32_t)(a > b ? a : b);
                tj[count] = (int32_t)(a > b ? b : a);
                tv[count++] = w;
            }
        }
    }
    for (k = 0; k < n; k++) {
        ti[count] = (int32_t)k; tj[count] = (int32_t)k; tv[count++] = 0.0;
    }
    err = dfm__from_triplets(n, n, count, ti, tj, tv,
                             kind == DFM_LAPLACIAN_UNIFORM_NORMALIZED ? DFM_CSC_GENERAL : DFM_CSC_SYMMETRIC_LOWER,
                             &al, out);
    if (err != DFM_OK) goto done;
    /* turn summed edge weights into Laplacian values */
    if (kind == DFM_LAPLACIAN_UNIFORM_NORMALIZED) {
        /* column j: entries (i, j) for neighbours i, and (j, j); row i is scaled by 1/d_i where
           d_i = number of distinct neighbours: count them per row first */
        size_t j, p;
        double *deg = tv; /* reuse (cap >= n) */
        for (k = 0; k < n; k++) deg[k] = 0.0;
        for (j = 0; j < n; j++)
            for (p = out->col_start[j]; p < out->col_start[j + 1]; p++)
                if ((size_t)out->row_index[p] != j) deg[out->row_index[p]] += 1.0;
        for (j = 0; j < n; j++)
            for (p = out->col_start[j]; p < out->col_start[j + 1]; p++) {
                size_t i = (size_t)out->row_index[p];
                if (i == j) out->values[p] = deg[i] > 0.0 ? 1.0 : 0.0;
                else out->values[p] = -1.0 / deg[i];
            }
    } else {
        size_t j, p;
        double *diag = tv;
        for (k = 0; k < n; k++) diag[k] = 0.0;
        for (j = 0; j < n; j++)
            for (p = out->col_start[j]; p < out->col_start[j + 1]; p++) {
                size_t i = (size_t)out->row_index[p];
                if (i == j) continue;
                if (kind == DFM_LAPLACIAN_UNIFORM) out->values[p] = 1.0;
                diag[i] += out->values[p];
                diag[j] += out->values[p];
                out->values[p] = -out->values[p];
            }
        for (j = 0; j < n; j++)
            for (p = out->col_start[j]; p < out->col_start[j + 1]; p++)
                if ((size_t)out->row_index[p] == j) out->values[p] = diag[j];
    }
done:
    dfm__free(&al, ti);
    dfm__free(&al, tj);
    dfm__free(&al, tv);
    if (err != DFM_OK) dfm_csc_free(out);
    return err;
}

/* Full (both triangles) copy of a symmetric-lower matrix, or a plain copy of a general one. */
static dfm_result dfm__expand_full(const dfm_csc *a, const dfm_allocator *al, dfm_csc *out)
{
    dfm_result err = DFM_OK;
    size_t j, p, nnz = a->col_start[a->n_cols], count = 0;
    int32_t *ti, *tj;
    double *tv;
    size_t cap = a->kind == DFM_CSC_SYMMETRIC_LOWER ? 2 * nnz : nnz;
    ti = (int32_t *)dfm__alloc(al, cap, sizeof(int32_t), &err);
    tj = (int32_t *)dfm__alloc(al, cap, sizeof(int32_t), &err);
    tv = (double *)dfm__alloc(al, cap, sizeof(double), &err);
    if (err == DFM_OK) {
        for (j = 0; j < a->n_cols; j++)
            for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
                int32_t i = a->row_index[p];
                ti[count] = i; tj[count] = (int32_t)j; tv[count++] = a->values[p];
                if (a->kind == DFM_CSC_SYMMETRIC_LOWER && (size_t)i != j) {
                    ti[count] = (int32_t)j; tj[count] = i; tv[count++] = a->values[p];
                }
            }
        err = dfm__from_triplets(a->n_rows, a->n_cols, count, ti, tj, tv, DFM_CSC_GENERAL, al, out);
    }
    dfm__free(al, ti);
    dfm__free(al, tj);
    dfm__free(al, tv);
    return err;
}

/* transpose of a general matrix (rows sorted, duplicates already merged) */
static dfm_result dfm__transpose(const dfm_csc *a, const dfm_allocator *al, dfm_csc *out)
{
    size_t j, p, nnz = a->col_start[a->n_cols];
    dfm_result err = dfm_csc_alloc(a->n_cols, a->n_rows, nnz, DFM_CSC_GENERAL, al, out);
    size_t *next;
    if (err != DFM_OK) return err;
    for (p = 0; p < nnz; p++) out->col_start[a->row_index[p] + 1]++;
    for (j = 0; j < a->n_rows; j++) out->col_start[j + 1] += out->col_start[j];
    next = (size_t *)dfm__alloc(al, a->n_rows + 1, sizeof(size_t), &err);
    if (!next) {
        dfm_csc_free(out);
        return err;
    }
    memcpy(next, out->col_start, (a->n_rows + 1) * sizeof(size_t));
    for (j = 0; j < a->n_cols; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            size_t q = next[a->row_index[p]]++;
            out->row_index[q] = (int32_t)j;
            out->values[q] = a->values[p];
        }
    dfm__free(al, next);
    return DFM_OK;
}

static void dfm__sort_int_double(int32_t *idx, double *val, size_t n)
{
    size_t i, j;
    for (i = 1; i < n; i++) {
        int32_t ki = idx[i];
        double kv = val ? val[i] : 0.0;
        for (j = i; j > 0 && idx[j - 1] > ki; j--) {
            idx[j] = idx[j - 1];
            if (val) val[j] = val[j - 1];
        }
        idx[j] = ki;
        if (val) val[j] = kv;
    }
}

DFMDEF dfm_result dfm_normal_matrix(const dfm_csc *a, const double *diagonal, const dfm_allocator *allocator,
                                    dfm_csc *out)
{
    dfm_allocator al = dfm__resolve_allocator(allocator);
    dfm_result err;
    dfm_csc full, rows; /* full = A by columns; rows = A^T by columns = A by rows */
    int32_t *mark = NULL;
    double *acc = NULL;
    size_t n, j, p, q, nnz;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    memset(&full, 0, sizeof full);
    memset(&rows, 0, sizeof rows);
    err = dfm_csc_validate(a);
    if (err != DFM_OK) return err;
    n = a->n_cols;
    if (n == 0) return DFM_ERR_INVALID_ARGUMENT;
    if (diagonal)
        for (j = 0; j < n; j++)
            if (!dfm__finite(diagonal[j])) return DFM_ERR_BAD_VALUE;
    err = dfm__expand_full(a, &al, &full);
    if (err == DFM_OK) err = dfm__transpose(&full, &al, &rows);
    if (err != DFM_OK) goto done;
    mark = (int32_t *)dfm__alloc(&al, n, sizeof(int32_t), &err);
    acc = (double *)dfm__alloc(&al, n, sizeof(double), &err);
    if (err != DFM_OK) goto done;
    /* pass 1: pattern size. Column j of A^T A has row k >= j when some row i of A holds both j
       and k, i.e. k in row i of A for i in column j of A. */
    for (j = 0; j < n; j++) mark[j] = -1;
    nnz = 0;
    for (j = 0; j < n; j++) {
        mark[j] = (int32_t)j;
        nnz++;
        for (p = full.col_start[j]; p < full.col_start[j + 1]; p++) {
            size_t i = (size_t)full.row_index[p];
            for (q = rows.col_start[i]; q < rows.col_start[i + 1]; q++) {
                int32_t k = rows.row_index[q];
                if ((size_t)k > j && mark[k] != (int32_t)j) {
                    mark[k] = (int32_t)j;
                    nnz++;
                }
            }
        }
    }
    err = dfm_csc_alloc(n, n, nnz, DFM_CSC_SYMMETRIC_LOWER, &al, out);
    if (err != DFM_OK) goto done;
    for (j = 0; j < n; j++) mark[j] = -1;
    nnz = 0;
    for (j = 0; j < n; j++) {
        size_t start = nnz;
        mark[j] = (int32_t)j;
        acc[j] = diagonal ? diagonal[j] : 0.0;
        out->row_index[nnz++] = (int32_t)j;
        for (p = full.col_start[j]; p < full.col_start[j + 1]; p++) {
            size_t i = (size_t)full.row_index[p];
            double aij = full.values[p];
            for (q = rows.col_start[i]; q < rows.col_start[i + 1]; q++) {
                int32_t k = rows.row_index[q];
                if ((size_t)k < j) continue;
                if (mark[k] != (int32_t)j) {
                    mark[k] = (int32_t)j;
                    acc[k] = 0.0;
                    out->row_index[nnz++] = k;
                }
                acc[k] += aij * rows.values[q];
            }
        }
        dfm__sort_int_double(out->row_index + start, NULL, nnz - start);
        for (q = start; q < nnz; q++) out->values[q] = acc[out->row_index[q]];
        out->col_start[j + 1] = nnz;
    }
    if (!dfm__all_finite(out->values, nnz)) err = DFM_ERR_NOT_FINITE; /* e.g. a 1e200 entry squared */
done:
    dfm_csc_free(&full);
    dfm_csc_free(&rows);
    dfm__free(&al, mark);
    dfm__free(&al, acc);
    if (err != DFM_OK) dfm_csc_free(out);
    return err;
}

DFMDEF dfm_result dfm_block_expand(const dfm_csc *g, size_t b, const double *blocks,
                                   const dfm_allocator *allocator, dfm_csc *out)
{
    dfm_allocator al = dfm__resolve_allocator(allocator);
    dfm_result err;
    size_t n, j, p, r, c, nnz = 0, w;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    err = dfm_csc_validate(g);
    if (err != DFM_OK) return err;
    if (g->kind != DFM_CSC_SYMMETRIC_LOWER || b == 0) return DFM_ERR_INVALID_ARGUMENT;
    n = g->n_cols;
    if (n > DFM__MAX_N / b) return DFM_ERR_TOO_LARGE;
    if (blocks)
        for (p = 0; p < g->col_start[n] * b * b; p++)
            if (!dfm__finite(blocks[p])) return DFM_ERR_BAD_VALUE;
    for (j = 0; j < n; j++)
        for (p = g->col_start[j]; p < g->col_start[j + 1]; p++)
            nnz += (size_t)g->row_index[p] == j ? b * (b + 1) / 2 : b * b;
    err = dfm_csc_alloc(n * b, n * b, nnz, DFM_CSC_SYMMETRIC_LOWER, &al, out);
    if (err != DFM_OK) return err;
    w = 0;
    for (j = 0; j < n; j++)
        for (c = 0; c < b; c++) {
            for (p = g->col_start[j]; p < g->col_start[j + 1]; p++) {
                size_t i = (size_t)g->row_index[p];
                for (r = (i == j ? c : 0); r < b; r++) {
                    out->row_index[w] = (int32_t)(b * i + r);
                    out->values[w] = blocks ? blocks[p * b * b + r * b + c] : (r == c ? g->values[p] : 0.0);
                    w++;
                }
            }
            out->col_start[b * j + c + 1] = w;
        }
    return DFM_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: approximate minimum degree (Amestoy, Davis, Duff 1996)

   The quotient graph: every node is a variable (uneliminated), an element (eliminated, standing
   for the clique of its remaining neighbours L_e) or absorbed. A variable i keeps one list in iw:
   first its elen[i] adjacent elements E_i, then its adjacent variables A_i. An element e keeps
   the list of variables L_e. Variables with identical lists are merged into supervariables of
   size nv[i]; a principal variable stands for all of them.
   --------------------------------------------------------------------------------------------- */

enum { DFM__VAR = 0, DFM__ELEM = 1, DFM__DEAD = 2 };

typedef struct dfm__amd {
    int32_t n;
    int32_t *iw;
    int64_t iwlen, pfree;
    int64_t *pe;
    int32_t *len, *elen, *nv, *degree, *status;
    int32_t *head, *next, *last;   /* degree lists */
    int64_t *w;                     /* |L_e \ L_p| scratch, wflg-relative */
    int32_t *hhead, *hnext;         /* hash buckets for supervariable detection */
    int64_t *hash, *mark;
    int32_t *first, *tail, *follow; /* members of each principal (for the final order) */
    int32_t *order_pivot;           /* pivots in elimination order */
    const int32_t *cset;            /* NULL, or constraint set of each node: lower sets first */
    int32_t level;                  /* the set pivots are taken from */
    unsigned char *inlist;          /* 1 while in a degree list (0: parked, later set) */
    const dfm_allocator *al;
    int64_t wflg, stamp;            /* the w[] offset and the mark[] stamp of the step */
    int64_t dense_limit;            /* rows denser than this are ordered last */
    int32_t nel, mindeg, dense_count; /* variables eliminated, the minimum degree, dense rows */
} dfm__amd;

static void dfm__amd_remove(dfm__amd *s, int32_t i)
{
    int32_t d = s->degree[i];
    if (!s->inlist[i]) return;
    s->inlist[i] = 0;
    if (s->last[i] >= 0) s->next[s->last[i]] = s->next[i];
    else s->head[d] = s->next[i];
    if (s->next[i] >= 0) s->last[s->next[i]] = s->last[i];
    s->next[i] = s->last[i] = -1;
}

static void dfm__amd_insert(dfm__amd *s, int32_t i, int32_t d)
{
    s->degree[i] = d;
    if (s->cset && s->cset[i] != s->level) return; /* parked until its set's turn */
    s->inlist[i] = 1;
    s->last[i] = -1;
    s->next[i] = s->head[d];
    if (s->head[d] >= 0) s->last[s->head[d]] = i;
    s->head[d] = i;
}

static int dfm__cmp_pe(const void *a, const void *b, const int64_t *pe)
{
    int64_t x = pe[*(const int32_t *)a], y = pe[*(const int32_t *)b];
    return x < y ? -1 : x > y;
}

/* Moves every live list to the front of iw, in order of position. */
static dfm_result dfm__amd_compact(dfm__amd *s, int64_t need)
{
    int32_t i, live = 0, *nodes;
    int64_t dst = 0;
    dfm_result err = DFM_OK;
    nodes = (int32_t *)dfm__alloc(s->al, (size_t)s->n, sizeof(int32_t), &err);
    if (!nodes) return err;
    for (i = 0; i < s->n; i++)
        if (s->status[i] != DFM__DEAD && s->pe[i] >= 0) nodes[live++] = i;
    /* sort live nodes by pe: a simple merge sort over an index array */
    {
        int32_t *tmp = (int32_t *)dfm__alloc(s->al, (size_t)(live > 0 ? live : 1), sizeof(int32_t), &err);
        int32_t width, lo;
        if (!tmp) {
            dfm__free(s->al, nodes);
            return err;
        }
        for (width = 1; width < live; width *= 2) {
            for (lo = 0; lo < live; lo += 2 * width) {
                int32_t mid = lo + width < live ? lo + width : live;
                int32_t hi = lo + 2 * width < live ? lo + 2 * width : live;
                int32_t a = lo, b = mid, k = lo;
                while (a < mid && b < hi) tmp[k++] = dfm__cmp_pe(&nodes[b], &nodes[a], s->pe) < 0 ? nodes[b++] : nodes[a++];
                while (a < mid) tmp[k++] = nodes[a++];
                while (b < hi) tmp[k++] = nodes[b++];
            }
            memcpy(nodes, tmp, (size_t)live * sizeof(int32_t));
        }
        dfm__free(s->al, tmp);
    }
    for (i = 0; i < live; i++) {
        int32_t v = nodes[i];
        int64_t src = s->pe[v], l = s->len[v];
        if (src != dst) memmove(s->iw + dst, s->iw + src, (size_t)l * sizeof(int32_t));
        s->pe[v] = dst;
        dst += l;
    }
    dfm__free(s->al, nodes);
    s->pfree = dst;
    if (s->iwlen - s->pfree < need) {
        /* grow */
        int64_t newlen = s->pfree + need + s->iwlen / 2;
        int32_t *niw = (int32_t *)dfm__alloc(s->al, (size_t)newlen, sizeof(int32_t), &err);
        if (!niw) return err;
        memcpy(niw, s->iw, (size_t)s->pfree * sizeof(int32_t));
        dfm__free(s->al, s->iw);
        s->iw = niw;
        s->iwlen = newlen;
    }
    return DFM_OK;
}

/* Appends the members of principal j to principal i's member list. */
static void dfm__amd_join(dfm__amd *s, int32_t i, int32_t j)
{
    if (s->first[j] < 0) return;
    if (s->first[i] < 0) s->first[i] = s->first[j];
    else s->follow[s->tail[i]] = s->first[j];
    s->tail[i] = s->tail[j];
    s->first[j] = s->tail[j] = -1;
}

static void dfm__amd_free(dfm__amd *s)
{
    const dfm_allocator *al = s->al;
    dfm__free(al, s->iw);
    dfm__free(al, s->pe);
    dfm__free(al, s->len);
    dfm__free(al, s->elen);
    dfm__free(al, s->nv);
    dfm__free(al, s->degree);
    dfm__free(al, s->status);
    dfm__free(al, s->head);
    dfm__free(al, s->next);
    dfm__free(al, s->last);
    dfm__free(al, s->w);
    dfm__free(al, s->hhead);
    dfm__free(al, s->hnext);
    dfm__free(al, s->hash);
    dfm__free(al, s->mark);
    dfm__free(al, s->first);
    dfm__free(al, s->tail);
    dfm__free(al, s->follow);
    dfm__free(al, s->order_pivot);
    dfm__free(al, s->inlist);
}

static dfm_result dfm__amd_alloc(dfm__amd *s, int32_t n, size_t nnz, const dfm_allocator *al)
{
    dfm_result err = DFM_OK;
    memset(s, 0, sizeof *s);
    s->n = n;
    s->al = al;
    s->iwlen = (int64_t)(nnz + nnz / 5 + (size_t)n + 16);
    s->iw = (int32_t *)dfm__alloc(al, (size_t)s->iwlen, sizeof(int32_t), &err);
    s->pe = (int64_t *)dfm__alloc(al, (size_t)n, sizeof(int64_t), &err);
    s->len = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->elen = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->nv = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->degree = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->status = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->head = (int32_t *)dfm__alloc(al, (size_t)n + 1, sizeof(int32_t), &err);
    s->next = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->last = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->w = (int64_t *)dfm__alloc(al, (size_t)n, sizeof(int64_t), &err);
    s->hhead = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->hnext = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->hash = (int64_t *)dfm__alloc(al, (size_t)n, sizeof(int64_t), &err);
    s->mark = (int64_t *)dfm__alloc(al, (size_t)n, sizeof(int64_t), &err);
    s->first = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->tail = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->follow = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->order_pivot = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    s->inlist = (unsigned char *)dfm__alloc(al, (size_t)n, 1, &err);
    if (err == DFM_OK) memset(s->inlist, 0, (size_t)n);
    return err;
}

/* The quotient graph at the start: every node a variable with its adjacency list; dense rows
   (degree > 10 sqrt(n), at least 16) are taken out and ordered last. */
static void dfm__amd_init(dfm__amd *s, const size_t *adj_start, const int32_t *adj, const int32_t *cset)
{
    int32_t i, n = s->n;
    s->cset = cset;
    s->level = 0;
    if (cset) {
        s->level = INT32_MAX;
        for (i = 0; i < n; i++)
            if (cset[i] < s->level) s->level = cset[i];
    }
    s->dense_limit = (int64_t)(10.0 * sqrt((double)n));
    if (s->dense_limit < 16) s->dense_limit = 16;
    for (i = 0; i < n; i++) {
        int64_t d = (int64_t)(adj_start[i + 1] - adj_start[i]);
        s->status[i] = d > s->dense_limit ? DFM__DEAD : DFM__VAR;
    }
    s->pfree = 0;
    for (i = 0; i < n; i++) {
        size_t p;
        s->pe[i] = s->pfree;
        s->len[i] = 0;
        s->elen[i] = 0;
        s->nv[i] = 1;
        s->w[i] = 1;
        s->hhead[i] = -1;
        s->mark[i] = 0;
        s->first[i] = s->tail[i] = i;
        s->follow[i] = -1;
        s->next[i] = s->last[i] = -1;
        if (s->status[i] == DFM__DEAD) {
            s->dense_count++;
            s->pe[i] = -1;
            continue;
        }
        for (p = adj_start[i]; p < adj_start[i + 1]; p++) {
            int32_t j = adj[p];
            if (j != i && s->status[j] != DFM__DEAD) s->iw[s->pfree++] = j;
        }
        s->len[i] = (int32_t)(s->pfree - s->pe[i]);
    }
    for (i = 0; i <= n; i++) s->head[i] = -1;
    for (i = 0; i < n; i++)
        if (s->status[i] == DFM__VAR) dfm__amd_insert(s, i, s->len[i]);
    s->wflg = 2;
}

/* Constrained ordering: the current set is done, the next set's variables enter the lists. */
static void dfm__amd_next_set(dfm__amd *s)
{
    int32_t i, n = s->n, next_level = INT32_MAX;
    for (i = 0; i < n; i++)
        if (s->status[i] == DFM__VAR && s->nv[i] > 0 && s->cset[i] > s->level && s->cset[i] < next_level)
            next_level = s->cset[i];
    s->level = next_level;
    s->mindeg = n;
    for (i = 0; i < n; i++)
        if (s->status[i] == DFM__VAR && s->nv[i] > 0 && s->cset[i] == next_level) {
            dfm__amd_insert(s, i, s->degree[i]);
            if (s->degree[i] < s->mindeg) s->mindeg = s->degree[i];
        }
}

/* Step 2: L_p = the union of p's elements' lists and A_p, stored as the new element p at pfree
   (iw[pme1 .. pme2)); the elements are absorbed into p. lp_nv: the variables in L_p. */
static dfm_result dfm__amd_form_element(dfm__amd *s, int32_t p, int64_t *pme1, int64_t *pme2, int32_t *lp_nv)
{
    int32_t e = -1, nvp = s->nv[p];
    int64_t need = s->len[p] - s->elen[p], q;
    for (q = s->pe[p]; q < s->pe[p] + s->elen[p]; q++) need += s->len[s->iw[q]];
    if (s->iwlen - s->pfree < need) {
        dfm_result err = dfm__amd_compact(s, need);
        if (err != DFM_OK) return err;
    }
    s->nv[p] = -nvp;
    *pme1 = s->pfree;
    *lp_nv = 0;
    for (q = s->pe[p]; q < s->pe[p] + s->len[p]; q++) {
        int32_t v = s->iw[q];
        int is_elem = q < s->pe[p] + s->elen[p];
        int64_t a, b;
        if (is_elem) {
            e = v;
            if (s->status[e] != DFM__ELEM) continue;
            a = s->pe[e];
            b = a + s->len[e];
        } else {
            a = q;
            b = q + 1;
        }
        for (; a < b; a++) {
            int32_t j = s->iw[a];
            if (s->status[j] != DFM__VAR || s->nv[j] <= 0) continue; /* eliminated, merged, or in L_p */
            s->iw[s->pfree++] = j;
            *lp_nv += s->nv[j];
            s->nv[j] = -s->nv[j];
            dfm__amd_remove(s, j);
        }
        if (is_elem) { /* e is absorbed into p */
            s->status[e] = DFM__DEAD;
            s->pe[e] = -1;
            s->w[e] = 0;
        }
    }
    *pme2 = s->pfree;
    s->status[p] = DFM__ELEM;
    s->pe[p] = *pme1;
    s->len[p] = (int32_t)(*pme2 - *pme1);
    s->elen[p] = 0;
    s->degree[p] = *lp_nv;
    return DFM_OK;
}

/* Step 3: |L_e \ L_p| for every element e next to a variable of L_p, as w[e] - wflg. */
static void dfm__amd_external(dfm__amd *s, int32_t p, int64_t pme1, int64_t pme2)
{
    int64_t q;
    int32_t i;
    if (s->wflg > INT64_MAX / 4) {
        for (i = 0; i < s->n; i++)
            if (s->w[i] != 0) s->w[i] = 1;
        s->wflg = 2;
    }
    for (q = pme1; q < pme2; q++) {
        int32_t v = s->iw[q], nvi = -s->nv[v];
        int64_t r;
        for (r = s->pe[v]; r < s->pe[v] + s->elen[v]; r++) {
            int64_t we;
            int32_t e = s->iw[r];
            if (s->status[e] != DFM__ELEM || e == p) continue;
            we = s->w[e];
            if (we >= s->wflg) we -= nvi;
            else we = (int64_t)s->degree[e] + s->wflg - nvi;
            s->w[e] = we;
        }
    }
}

/* Step 4: prune each variable's lists (aggressive absorption, mass elimination), keep its
   external degree in w[v] and hash it into the buckets. */
static void dfm__amd_prune(dfm__amd *s, int32_t p, int64_t pme1, int64_t pme2, int32_t *lp_nv)
{
    int64_t q;
    for (q = pme1; q < pme2; q++) {
        int32_t v = s->iw[q], ne = 0, nvi = -s->nv[v], pend = p;
        int64_t r, pos, start = s->pe[v], deg = 0, h = 0;
        int32_t old_elen = s->elen[v], old_len = s->len[v];
        /* the kept entries go one slot later, after p: each is written when the next one is read
           (a slot is only written once read), the last one after the loops. There is room: the
           list dropped p itself or an element absorbed into p (adjacency in the quotient graph
           is symmetric) */
        pos = start;
        for (r = start; r < start + old_elen; r++) {
            int64_t we;
            int32_t e = s->iw[r];
            if (s->status[e] != DFM__ELEM || e == p) continue;
            we = s->w[e] - s->wflg;
            if (we <= 0) { /* aggressive absorption: L_e is inside L_p */
                s->status[e] = DFM__DEAD;
                s->pe[e] = -1;
                s->w[e] = 0;
                continue;
            }
            deg += we;
            h += e;
            s->iw[pos++] = pend;
            pend = e;
            ne++;
        }
        for (r = start + old_elen; r < start + old_len; r++) {
            int32_t j = s->iw[r];
            if (s->status[j] != DFM__VAR || s->nv[j] <= 0) continue; /* gone, merged or in L_p */
            deg += s->nv[j];
            h += j;
            s->iw[pos++] = pend;
            pend = j;
        }
        s->iw[pos++] = pend;
        s->elen[v] = ne + 1;
        s->len[v] = (int32_t)(pos - start);
        if (s->elen[v] == 1 && s->len[v] == 1) { /* mass elimination: v is adjacent to p only */
            s->nv[v] = 0;
            s->status[v] = DFM__DEAD;
            s->pe[v] = -1;
            s->nel += nvi;
            *lp_nv -= nvi;
            dfm__amd_join(s, p, v);
            continue;
        }
        s->w[v] = deg; /* external part, without L_p; degree[] still holds the old bound */
        h %= s->n;
        s->hash[v] = h;
        s->hnext[v] = s->hhead[h];
        s->hhead[h] = v;
    }
    s->degree[p] = *lp_nv;
}

/* Step 5 for one bucket: the variables with the same lists as a, merged into a. */
static void dfm__amd_merge_bucket(dfm__amd *s, int32_t a)
{
    while (a >= 0) {
        int32_t b = s->hnext[a], prev = a;
        int64_t r;
        if (s->status[a] != DFM__VAR) {
            a = b;
            continue;
        }
        s->stamp++; /* mark a's list, then compare each later list of the bucket with it */
        for (r = s->pe[a] + 1; r < s->pe[a] + s->len[a]; r++) s->mark[s->iw[r]] = s->stamp;
        while (b >= 0) {
            int32_t bn = s->hnext[b];
            int same = s->status[b] == DFM__VAR && s->len[b] == s->len[a] && s->elen[b] == s->elen[a] &&
                       (!s->cset || s->cset[a] == s->cset[b]);
            if (same)
                for (r = s->pe[b] + 1; r < s->pe[b] + s->len[b]; r++)
                    if (s->mark[s->iw[r]] != s->stamp) {
                        same = 0;
                        break;
                    }
            if (same) { /* b joins a */
                s->nv[a] += s->nv[b]; /* both negative */
                s->nv[b] = 0;
                s->status[b] = DFM__DEAD;
                s->pe[b] = -1;
                dfm__amd_join(s, a, b);
                s->hnext[prev] = bn;
            } else {
                prev = b;
            }
            b = bn;
        }
        a = s->hnext[a];
    }
}

/* Step 5: supervariables: variables of L_p with equal lists (same hash bucket) are merged. */
static void dfm__amd_supervariables(dfm__amd *s, int64_t pme1, int64_t pme2)
{
    int64_t q;
    for (q = pme1; q < pme2; q++) {
        int32_t v = s->iw[q], h, a;
        if (s->status[v] != DFM__VAR || s->nv[v] == 0) continue;
        h = (int32_t)s->hash[v];
        if (s->hhead[h] < 0) continue;
        a = s->hhead[h];
        s->hhead[h] = -1;
        dfm__amd_merge_bucket(s, a);
    }
}

/* Step 6: the approximate degrees (ADD 1996, eq. 4.1), back into the degree lists; L_p
   compacted to its live variables. */
static void dfm__amd_degrees(dfm__amd *s, int32_t p, int64_t pme1, int64_t pme2, int32_t lp_nv)
{
    int64_t q, wpos = pme1;
    for (q = pme1; q < pme2; q++) {
        int32_t v = s->iw[q], nvi;
        int64_t d, d2, rest;
        if (s->status[v] != DFM__VAR || s->nv[v] == 0) continue;
        nvi = -s->nv[v];
        rest = (int64_t)(s->n - s->nel) - nvi;
        d = s->w[v] + lp_nv - nvi;
        d2 = (int64_t)s->degree[v] + lp_nv - nvi;
        if (d2 < d) d = d2;
        if (rest < d) d = rest;
        if (d < 0) d = 0;
        s->nv[v] = nvi;
        s->w[v] = 1;
        dfm__amd_insert(s, v, (int32_t)d);
        if (d < s->mindeg) s->mindeg = (int32_t)d;
        s->iw[wpos++] = v;
    }
    s->len[p] = (int32_t)(wpos - pme1);
    s->pfree = wpos;
}

/* The order: each pivot's members (the pivot, its supervariable, mass eliminations), then the
   dense rows. */
static dfm_result dfm__amd_permutation(const dfm__amd *s, int32_t npivots, const size_t *adj_start, int32_t *perm)
{
    int32_t i, k = 0;
    for (i = 0; i < npivots; i++) {
        int32_t v;
        for (v = s->first[s->order_pivot[i]]; v >= 0; v = s->follow[v]) perm[k++] = v;
    }
    for (i = 0; i < s->n; i++)
        if (s->status[i] == DFM__DEAD && (int64_t)(adj_start[i + 1] - adj_start[i]) > s->dense_limit) perm[k++] = i;
    return k == s->n ? DFM_OK : DFM_ERR_INVALID_ARGUMENT; /* cannot happen: every node once */
}

/* The fill of an ordering as AMD sees it: nnz(L) with the diagonal, and sum of the squared
   column counts (CHOLMOD's flop measure). Exact when no dense row was set aside: the element
   formed at a pivot is exactly the pivot's column structure below the pivot's supervariable. */
typedef struct dfm__fill {
    double lnz, flops;
    int exact;
} dfm__fill;

/* f columns eliminated together above r rows: counts r + f, r + f - 1, ..., r + 1 */
static void dfm__fill_add(dfm__fill *fl, int64_t f, int64_t r)
{
    int64_t c;
    for (c = r + 1; c <= r + f; c++) {
        fl->lnz += (double)c;
        fl->flops += (double)c * (double)c;
    }
}

/* AMD on the pattern of a symmetric graph given by full adjacency (both directions, no
   diagonal): adj_start[n+1], adj. perm[k] = node eliminated k-th. With cset (constrained
   minimum degree, as in CAMD), pivots come from the lowest constraint set that has variables
   left; supervariables never mix sets. fill (or NULL) receives the ordering's fill. */
static dfm_result dfm__amd_order(int32_t n, const size_t *adj_start, const int32_t *adj, const int32_t *cset,
                                 const dfm_allocator *al, int (*progress)(void *, float), void *puser, int32_t *perm,
                                 dfm__fill *fill, int32_t *count)
{
    dfm__amd S, *s = &S;
    int32_t npivots = 0, k;
    dfm__fill fl = {0.0, 0.0, 0};
    dfm_result err = dfm__amd_alloc(s, n, adj_start[n], al);
    if (err == DFM_OK) dfm__amd_init(s, adj_start, adj, cset);
    while (err == DFM_OK && s->nel < n - s->dense_count) {
        int32_t p, nvp, lp_nv, nel0 = s->nel;
        int64_t pme1, pme2;
        /* 1. the variable of minimum approximate degree */
        while (s->mindeg < n && s->head[s->mindeg] < 0) s->mindeg++;
        if (s->mindeg >= n && cset) {
            dfm__amd_next_set(s);
            continue;
        }
        p = s->head[s->mindeg];
#ifdef DFM_TEST_AMD_PIVOT
        DFM_TEST_AMD_PIVOT(s, p); /* test-only: the degree lists checked before each pivot */
#endif
        dfm__amd_remove(s, p);
        nvp = s->nv[p];
        s->order_pivot[npivots++] = p;
        s->nel += nvp;
        if (progress && (npivots & 1023) == 0 && progress(puser, 0.5f * (float)s->nel / (float)n)) {
            err = DFM_CANCELLED;
            break;
        }
        err = dfm__amd_form_element(s, p, &pme1, &pme2, &lp_nv); /* 2 */
        if (err != DFM_OK) break;
        dfm__amd_external(s, p, pme1, pme2);                      /* 3 */
        dfm__amd_prune(s, p, pme1, pme2, &lp_nv);                 /* 4 */
        dfm__amd_supervariables(s, pme1, pme2);                   /* 5 */
        dfm__amd_degrees(s, p, pme1, pme2, lp_nv);                /* 6 */
#ifdef DFM_TEST_AMD_STEP
        DFM_TEST_AMD_STEP(s, p); /* test-only: the new degrees checked against the quotient graph */
#endif
        dfm__fill_add(&fl, s->nel - nel0, (int64_t)lp_nv + s->dense_count);
        if (count) { /* the pivot's members, in their order: r + f, r + f - 1, ... */
            int32_t v, c = s->nel - nel0 + lp_nv + s->dense_count;
            for (v = s->first[p]; v >= 0; v = s->follow[v]) count[v] = c--;
        }
        s->nv[p] = nvp;
        if (s->len[p] == 0) { /* an element with nothing left: a root */
            s->status[p] = DFM__DEAD;
            s->pe[p] = -1;
        }
        s->wflg += n + 1;
    }
    if (err == DFM_OK) err = dfm__amd_permutation(s, npivots, adj_start, perm);
    if (err == DFM_OK && count)
        for (k = n - s->dense_count; k < n; k++) count[perm[k]] = n - k;
    dfm__fill_add(&fl, s->dense_count, 0);
    fl.exact = s->dense_count == 0;
    if (fill) *fill = fl;
    dfm__amd_free(s);
    return err;
}

/* ---------------------------------------------------------------------------------------------
   Section: nested dissection by geometric separators

   Recursive coordinate bisection of the graph: a part is split at the median of the coordinate
   (x, y or z) whose median cut crosses the fewest edges, the part's nodes on one side that touch the other side (the smaller of the two
   boundaries) form the separator, ordered after both halves (George 1973). Parts below
   DFM__ND_LEAF nodes are not split further. The order within the dissection comes from
   constrained minimum degree on the whole graph (as CHOLMOD's nesdis does with CAMD): the
   leaves first, then the separators from the deepest to the root one, each set ordered by
   approximate minimum degree, so that leaf nodes next to a separator are eliminated knowing it.
   The analysis keeps whichever of this and plain AMD gives the smaller nnz(L).
   --------------------------------------------------------------------------------------------- */

#ifndef DFM__ND_LEAF
#define DFM__ND_LEAF 128
#endif

typedef struct dfm__nd_task {
    size_t lo, hi; /* nodes[lo..hi) are the part */
    int32_t depth;
} dfm__nd_task;

/* k-th smallest of ids[0..n) by (key, id): quickselect, deterministic pivots (median of three) */
static void dfm__select(int32_t *ids, size_t n, size_t k, const double *coords, int axis)
{
    size_t lo = 0, hi = n; /* the k-th lies in [lo, hi) */
#define DFM__KEY_LESS(a, b) (coords[3 * (size_t)(a) + axis] < coords[3 * (size_t)(b) + axis] || \
    (coords[3 * (size_t)(a) + axis] == coords[3 * (size_t)(b) + axis] && (a) < (b)))
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2, i, store;
        int32_t a = ids[lo], b = ids[mid], c = ids[hi - 1], pivot, t;
        /* median of three */
        if (DFM__KEY_LESS(b, a)) { t = a; a = b; b = t; }
        if (DFM__KEY_LESS(c, b)) { t = b; b = c; c = t; }
        if (DFM__KEY_LESS(b, a)) { t = a; a = b; b = t; }
        pivot = b;
        /* three-way partition is not needed: keys are distinct with the id tie-break */
        for (i = lo; i < hi; i++)
            if (ids[i] == pivot) {
                ids[i] = ids[hi - 1];
                ids[hi - 1] = pivot;
                break;
            }
        store = lo;
        for (i = lo; i + 1 < hi; i++)
            if (DFM__KEY_LESS(ids[i], pivot)) {
                t = ids[i];
                ids[i] = ids[store];
                ids[store] = t;
                store++;
            }
        ids[hi - 1] = ids[store];
        ids[store] = pivot;
        if (store == k) return;
        if (k < store) hi = store;
        else lo = store + 1;
    }
#undef DFM__KEY_LESS
}

/* The axis whose median cut of part (m nodes, those with tag == stamp) crosses the fewest
   edges; side[] is scratch. */
static int dfm__nd_best_axis(int32_t *part, size_t m, const size_t *adj_start, const int32_t *adj,
                             const double *coords, const int32_t *tag, int32_t stamp, int32_t *side)
{
    size_t best = (size_t)-1, half = m / 2, i, p;
    int ax, axis = 0;
    for (ax = 0; ax < 3; ax++) {
        size_t cut = 0;
        dfm__select(part, m, half, coords, ax);
        for (i = 0; i < m; i++) side[part[i]] = i < half ? 0 : 1;
        for (i = 0; i < half; i++)
            for (p = adj_start[part[i]]; p < adj_start[part[i] + 1]; p++) cut += tag[adj[p]] == stamp && side[adj[p]] == 1;
        if (cut < best) {
            best = cut;
            axis = ax;
        }
    }
    return axis;
}

/* The boundary of each side: nodes with a neighbour on the other side get side |= 2; nl and nr
   count them. */
static void dfm__nd_boundary(const int32_t *part, size_t m, const size_t *adj_start, const int32_t *adj,
                             const int32_t *tag, int32_t stamp, int32_t *side, size_t *nl, size_t *nr)
{
    size_t i, p;
    *nl = *nr = 0;
    for (i = 0; i < m; i++) {
        int32_t v = part[i];
        for (p = adj_start[v]; p < adj_start[v + 1]; p++) {
            int32_t u = adj[p];
            if (tag[u] == stamp && (side[u] & 1) != (side[v] & 1)) {
                if (side[v] < 2) {
                    if (side[v] == 0) (*nl)++;
                    else (*nr)++;
                }
                side[v] |= 2;
                break;
            }
        }
    }
}

/* Reorders part as [side 0 without separator][side 1 without separator][separator] (the
   separator: sep_side's boundary); *a = the first group's size, *s0 = the separator's start. */
static void dfm__nd_layout(int32_t *part, size_t m, const int32_t *side, int32_t sep_side, int32_t *tmp, size_t *a,
                           size_t *s0)
{
    size_t k, b;
    *a = 0;
    for (k = 0; k < m; k++) {
        int32_t v = part[k];
        int sd = side[v] & 1, bd = side[v] >> 1;
        if (sd == 0 && !(bd && sep_side == 0)) tmp[(*a)++] = v;
    }
    b = *a;
    for (k = 0; k < m; k++) {
        int32_t v = part[k];
        int sd = side[v] & 1, bd = side[v] >> 1;
        if (sd == 1 && !(bd && sep_side == 1)) tmp[b++] = v;
    }
    *s0 = b;
    for (k = 0; k < m; k++) {
        int32_t v = part[k];
        int sd = side[v] & 1, bd = side[v] >> 1;
        if (bd && sd == sep_side) tmp[b++] = v;
    }
    memcpy(part, tmp, m * sizeof(int32_t));
}

static dfm_result dfm__nd_order(int32_t n, const size_t *adj_start, const int32_t *adj, const double *coords,
                                const dfm_allocator *al, int (*progress)(void *, float), void *puser, int32_t *perm,
                                dfm__fill *fill, int32_t *count)
{
    dfm_result err = DFM_OK;
    int32_t *nodes = NULL, *tag = NULL, *side = NULL, *local = NULL, *cset = NULL, stamp = 0;
    dfm__nd_task *stack = NULL;
    size_t top = 0, i, done = 0, cap = 2 * (size_t)n + 2;
    nodes = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    tag = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    side = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    local = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    stack = (dfm__nd_task *)dfm__alloc(al, cap, sizeof(dfm__nd_task), &err);
    cset = (int32_t *)dfm__alloc(al, (size_t)n, sizeof(int32_t), &err);
    if (err != DFM_OK) goto done;
    for (i = 0; i < (size_t)n; i++) {
        nodes[i] = (int32_t)i;
        tag[i] = 0;
        cset[i] = 0;
    }
    stack[top].lo = 0;
    stack[top].depth = 0;
    stack[top++].hi = (size_t)n;
    while (top > 0) {
        dfm__nd_task tk = stack[--top];
        size_t m = tk.hi - tk.lo, half = m / 2, nl, nr, a, s0, k;
        int32_t *part = nodes + tk.lo;
        int axis;
        stamp++;
        for (i = 0; i < m; i++) tag[part[i]] = stamp;
        if (m <= DFM__ND_LEAF) {
            done += m;
            if (progress && (stamp & 255) == 0 && progress(puser, 0.2f * (float)done / (float)n)) {
                err = DFM_CANCELLED;
                goto done;
            }
            continue;
        }
        axis = dfm__nd_best_axis(part, m, adj_start, adj, coords, tag, stamp, side);
        dfm__select(part, m, half, coords, axis);
        for (i = 0; i < m; i++) side[part[i]] = i < half ? 0 : 1;
        dfm__nd_boundary(part, m, adj_start, adj, tag, stamp, side, &nl, &nr);
        /* separator = the smaller boundary; the other boundary's nodes stay in their half */
        dfm__nd_layout(part, m, side, nl <= nr ? 0 : 1, local, &a, &s0);
        /* the separator comes after both halves and after every deeper separator */
        for (k = s0; k < m; k++) cset[part[k]] = INT32_MAX / 2 - tk.depth;
        done += m - s0;
        if (top + 2 > cap) { /* cannot happen: each task splits into smaller ones */
            err = DFM_ERR_INVALID_ARGUMENT;
            goto done;
        }
        if (s0 > a) {
            stack[top].lo = tk.lo + a;
            stack[top].depth = tk.depth + 1;
            stack[top++].hi = tk.lo + s0;
        }
        if (a > 0) {
            stack[top].lo = tk.lo;
            stack[top].depth = tk.depth + 1;
            stack[top++].hi = tk.lo + a;
        }
    }
    err = dfm__amd_order(n, adj_start, adj, cset, al, progress, puser, perm, fill, count);
done:
    dfm__free(al, nodes);
    dfm__free(al, tag);
    dfm__free(al, side);
    dfm__free(al, local);
    dfm__free(al, stack);
    dfm__free(al, cset);
    return err;
}

/* nnz(L) of a graph (adjacency without diagonal) under an ordering: elimination tree, then row
   subtrees. perm[k] = node eliminated k-th. */
static dfm_result dfm__graph_fill(size_t n, const size_t *adj_start, const int32_t *adj, const int32_t *perm,
                                  const dfm_allocator *al, double *nnz_out)
{
    dfm_result err = DFM_OK;
    int32_t *ip = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    int32_t *parent = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    int32_t *anc = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    size_t k, p;
    double total = 0.0;
    if (err == DFM_OK) {
        for (k = 0; k < n; k++) ip[perm[k]] = (int32_t)k;
        for (k = 0; k < n; k++) {
            int32_t v = perm[k];
            parent[k] = -1;
            anc[k] = -1;
            for (p = adj_start[v]; p < adj_start[v + 1]; p++) {
                int32_t r = ip[adj[p]];
                while (r != -1 && r < (int32_t)k) {
                    int32_t next = anc[r];
                    anc[r] = (int32_t)k;
                    if (next == -1) parent[r] = (int32_t)k;
                    r = next;
                }
            }
        }
        for (k = 0; k < n; k++) anc[k] = -1;
        for (k = 0; k < n; k++) {
            int32_t v = perm[k];
            anc[k] = (int32_t)k;
            total += 1.0;
            for (p = adj_start[v]; p < adj_start[v + 1]; p++) {
                int32_t x = ip[adj[p]];
                if (x > (int32_t)k) continue;
                while (anc[x] != (int32_t)k) {
                    anc[x] = (int32_t)k;
                    total += 1.0;
                    x = parent[x];
                }
            }
        }
    }
    dfm__free(al, ip);
    dfm__free(al, parent);
    dfm__free(al, anc);
    *nnz_out = total;
    return err;
}

/* ---------------------------------------------------------------------------------------------
   Section: symbolic analysis (elimination tree, postorder, column counts, supernodes)
   --------------------------------------------------------------------------------------------- */

struct dfm_chol {
    dfm_allocator al;
    int (*progress)(void *user, float done);
    void *progress_user;
    size_t n, nnz_a;
    uint64_t pattern_hash;
    int32_t *perm, *iperm;   /* perm[k] = input index of column k; iperm its inverse */
    size_t nsuper;
    int32_t *sup_first;      /* nsuper + 1: first column of each supernode */
    size_t *sup_rowptr;      /* nsuper + 1: into rows */
    int32_t *rows;           /* each supernode's rows (new numbering), sorted; its columns first */
    size_t *sup_valptr;      /* nsuper + 1: into values; block nrows x ncols column-major */
    double *values;
    int32_t *col_super;      /* n: supernode of each column */
    size_t *amap_start;      /* n + 1: A's entries by new column */
    size_t *amap_src;        /* nnz(A): index into a->values */
    size_t *amap_dst;        /* nnz(A): index into values */
    size_t max_update;       /* doubles of the largest descendant update */
    size_t max_rows;         /* rows of the tallest supernode */
    size_t *colcount;        /* n: entries of each column of L (new numbering) */
    size_t nnz_l;
    double flops;
    int factored;
    long long failed_column;
};

static uint64_t dfm__pattern_hash(const dfm_csc *a)
{
    uint64_t h = 1469598103934665603ull ^ (uint64_t)a->n_cols;
    size_t j, p;
    for (j = 0; j <= a->n_cols; j++) h = (h ^ (uint64_t)a->col_start[j]) * 1099511628211ull;
    for (p = 0; p < a->col_start[a->n_cols]; p++) h = (h ^ (uint64_t)(uint32_t)a->row_index[p]) * 1099511628211ull;
    return h;
}

DFMDEF dfm_chol_options dfm_chol_default_options(void)
{
    dfm_chol_options o;
    memset(&o, 0, sizeof o);
    o.ordering = DFM_ORDER_AMD;
    o.block_size = 1;
    return o;
}

DFMDEF void dfm_chol_free(dfm_chol *c)
{
    dfm_allocator al;
    if (!c) return;
    al = c->al;
    dfm__free(&al, c->perm);
    dfm__free(&al, c->iperm);
    dfm__free(&al, c->sup_first);
    dfm__free(&al, c->sup_rowptr);
    dfm__free(&al, c->rows);
    dfm__free(&al, c->sup_valptr);
    dfm__free(&al, c->values);
    dfm__free(&al, c->col_super);
    dfm__free(&al, c->amap_start);
    dfm__free(&al, c->amap_src);
    dfm__free(&al, c->amap_dst);
    dfm__free(&al, c->colcount);
    dfm__free(&al, c);
}

/* Graph of A + A^T without the diagonal, each node's neighbours distinct; with b > 1 the graph of
   the n / b vertex blocks (node i = rows b*i .. b*i + b - 1). */
static dfm_result dfm__adjacency(const dfm_csc *a, size_t b, const dfm_allocator *al, size_t **start_out,
                                 int32_t **adj_out)
{
    dfm_result err = DFM_OK;
    size_t nb = a->n_cols / b, j, p, total = 0;
    size_t *start = NULL, *fill = NULL;
    int32_t *adj = NULL, *mark = NULL;
    *start_out = NULL;
    *adj_out = NULL;
    start = (size_t *)dfm__alloc(al, nb + 1, sizeof(size_t), &err);
    fill = (size_t *)dfm__alloc(al, nb + 1, sizeof(size_t), &err);
    mark = (int32_t *)dfm__alloc(al, nb, sizeof(int32_t), &err);
    if (err != DFM_OK) goto fail;
    memset(start, 0, (nb + 1) * sizeof(size_t));
    for (j = 0; j < a->n_cols; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            size_t i = (size_t)a->row_index[p] / b, jj = j / b;
            if (i != jj) {
                start[i + 1]++;
                start[jj + 1]++;
                total += 2;
            }
        }
    for (j = 0; j < nb; j++) start[j + 1] += start[j];
    adj = (int32_t *)dfm__alloc(al, total, sizeof(int32_t), &err);
    if (err != DFM_OK) goto fail;
    memcpy(fill, start, (nb + 1) * sizeof(size_t));
    for (j = 0; j < a->n_cols; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            size_t i = (size_t)a->row_index[p] / b, jj = j / b;
            if (i != jj) {
                adj[fill[i]++] = (int32_t)jj;
                adj[fill[jj]++] = (int32_t)i;
            }
        }
    /* remove duplicates, compacting in place */
    for (j = 0; j < nb; j++) mark[j] = -1;
    total = 0;
    for (j = 0; j < nb; j++) {
        size_t s = start[j], e = fill[j];
        start[j] = total;
        for (p = s; p < e; p++) {
            int32_t i = adj[p];
            if (mark[i] == (int32_t)j) continue;
            mark[i] = (int32_t)j;
            adj[total++] = i;
        }
    }
    start[nb] = total;
    dfm__free(al, fill);
    dfm__free(al, mark);
    *start_out = start;
    *adj_out = adj;
    return DFM_OK;
fail:
    dfm__free(al, start);
    dfm__free(al, fill);
    dfm__free(al, mark);
    dfm__free(al, adj);
    return err;
}

/* The upper pattern of P A P^T by columns: column c lists rows r < c (from A's lower entries). */
static dfm_result dfm__permuted_upper(const dfm_csc *a, const int32_t *iperm, const dfm_allocator *al, size_t **ustart,
                                      int32_t **urows)
{
    dfm_result err = DFM_OK;
    size_t n = a->n_cols, j, p;
    size_t *st = (size_t *)dfm__alloc(al, n + 2, sizeof(size_t), &err);
    int32_t *ur = (int32_t *)dfm__alloc(al, a->col_start[n], sizeof(int32_t), &err);
    *ustart = NULL;
    *urows = NULL;
    if (err != DFM_OK) {
        dfm__free(al, st);
        dfm__free(al, ur);
        return err;
    }
    memset(st, 0, (n + 2) * sizeof(size_t));
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            int32_t I = iperm[a->row_index[p]], J = iperm[j];
            if (I != J) st[(I > J ? I : J) + 2]++;
        }
    for (j = 0; j < n; j++) st[j + 2] += st[j + 1];
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            int32_t I = iperm[a->row_index[p]], J = iperm[j];
            if (I != J) ur[st[(I > J ? I : J) + 1]++] = I > J ? J : I;
        }
    *ustart = st; /* st[c] .. st[c+1] is column c */
    *urows = ur;
    return DFM_OK;
}

/* Elimination tree (Liu 1990) from the upper pattern, with path-compressed ancestors. */
static void dfm__etree(size_t n, const size_t *ust, const int32_t *ur, int32_t *parent, int32_t *ancestor)
{
    size_t c, p;
    for (c = 0; c < n; c++) {
        parent[c] = -1;
        ancestor[c] = -1;
        for (p = ust[c]; p < ust[c + 1]; p++) {
            int32_t r = ur[p];
            while (r != -1 && r < (int32_t)c) {
                int32_t next = ancestor[r];
                ancestor[r] = (int32_t)c;
                if (next == -1) parent[r] = (int32_t)c;
                r = next;
            }
        }
    }
}

/* Postorder of a forest: children visited in increasing order. post[k] = k-th node. */
static void dfm__postorder(size_t n, const int32_t *parent, int32_t *head, int32_t *next, int32_t *stack, int32_t *post)
{
    size_t j, k = 0;
    for (j = 0; j < n; j++) head[j] = -1;
    for (j = n; j-- > 0;)
        if (parent[j] != -1) {
            next[j] = head[parent[j]];
            head[parent[j]] = (int32_t)j;
        }
    for (j = 0; j < n; j++) {
        int32_t top = 0;
        if (parent[j] != -1) continue;
        stack[0] = (int32_t)j;
        while (top >= 0) {
            int32_t v = stack[top], c = head[v];
            if (c == -1) {
                post[k++] = v;
                top--;
            } else {
                head[v] = next[c];
                stack[++top] = c;
            }
        }
    }
}

static size_t dfm__trapezoid(size_t ncols, size_t nrows) { return ncols * nrows - ncols * (ncols - 1) / 2; }

static int dfm__relax_merge(size_t ncols, size_t entries, size_t zeros)
{
    double z = entries > 0 ? (double)zeros / (double)entries : 0.0;
    if (ncols <= 4) return 1;
    if (ncols <= 16 && z < 0.8) return 1;
    if (ncols <= 48 && z < 0.1) return 1;
    return z < 0.05;
}

static int dfm__cmp_i32(const void *x, const void *y)
{
    int32_t a = *(const int32_t *)x, b = *(const int32_t *)y;
    return a < b ? -1 : a > b;
}

/* Ascending sort of distinct row indices without qsort's comparison calls: quicksort (median of
   three, Hoare partition, the smaller part first so the stack stays below 64), insertion sort
   below 16 entries. Distinct keys: every correct sort gives the same result. */
static void dfm__sort_rows(int32_t *a, size_t n)
{
    size_t stack[128], top = 0, lo = 0, hi = n, i, j;
    for (;;) {
        while (hi - lo > 16) {
            int32_t x = a[lo], y = a[lo + (hi - lo) / 2], z = a[hi - 1], piv, t;
            piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
            i = lo - 1;
            j = hi;
            for (;;) {
                do i++; while (a[i] < piv);
                do j--; while (a[j] > piv);
                if (i >= j) break;
                t = a[i];
                a[i] = a[j];
                a[j] = t;
            }
            if (j + 1 - lo < hi - j - 1) { /* [lo, j] and [j + 1, hi) */
                stack[top++] = j + 1;
                stack[top++] = hi;
                hi = j + 1;
            } else {
                stack[top++] = lo;
                stack[top++] = j + 1;
                lo = j + 1;
            }
        }
        for (i = lo + 1; i < hi; i++) {
            int32_t v = a[i];
            for (j = i; j > lo && a[j - 1] > v; j--) a[j] = a[j - 1];
            a[j] = v;
        }
        if (top == 0) break;
        hi = stack[--top];
        lo = stack[--top];
    }
}

/* Workspace of the symbolic analysis, one home for every temporary array (freed together). */
typedef struct dfm__symbolic {
    size_t *ust;        /* n + 2: the upper pattern of the permuted matrix by columns ... */
    int32_t *ur;        /* ... and its rows */
    int32_t *parent;    /* n: elimination tree */
    int32_t *w1, *w2, *w3, *post, *order; /* n + 1 each: marks, lists, stacks, orderings */
    size_t *count;      /* n: column counts of L */
    size_t nf;          /* fundamental supernodes */
    size_t *fstart;     /* nf + 1: their first columns */
    size_t *gcols, *grows, *gzeros, *gnext; /* relaxed groups of fundamental supernodes */
    int32_t *arow;      /* nnz(A): the new row of each of A's entries, grouped by new column */
    int32_t *relmap, *buf; /* n: relative row positions, gathered rows */
    int32_t *node_count;   /* NULL, or n: column counts by input index, exact, from the ordering */
} dfm__symbolic;

static void dfm__symbolic_free(dfm__symbolic *s, const dfm_allocator *al)
{
    dfm__free(al, s->ust);
    dfm__free(al, s->ur);
    dfm__free(al, s->parent);
    dfm__free(al, s->w1);
    dfm__free(al, s->w2);
    dfm__free(al, s->w3);
    dfm__free(al, s->post);
    dfm__free(al, s->order);
    dfm__free(al, s->count);
    dfm__free(al, s->fstart);
    dfm__free(al, s->gcols);
    dfm__free(al, s->grows);
    dfm__free(al, s->gzeros);
    dfm__free(al, s->gnext);
    dfm__free(al, s->arow);
    dfm__free(al, s->relmap);
    dfm__free(al, s->buf);
    dfm__free(al, s->node_count);
    memset(s, 0, sizeof *s);
}

/* Step 0: the arguments, and a diagonal entry in every column (else A cannot be definite). */
static dfm_result dfm__analyze_check(const dfm_csc *a, const dfm_chol_options *opt)
{
    size_t n, j, p, b;
    dfm_result err = dfm__validate_pattern(a);
    if (err != DFM_OK) return err;
    if (a->kind != DFM_CSC_SYMMETRIC_LOWER || a->n_cols == 0) return DFM_ERR_INVALID_ARGUMENT;
    n = a->n_cols;
    b = opt->block_size > 1 ? opt->block_size : 1;
    if (n % b != 0) return DFM_ERR_INVALID_ARGUMENT;
    if (opt->ordering < DFM_ORDER_AMD || opt->ordering > DFM_ORDER_GIVEN) return DFM_ERR_INVALID_ARGUMENT;
    if (opt->ordering == DFM_ORDER_GIVEN && !opt->perm) return DFM_ERR_INVALID_ARGUMENT;
    for (j = 0; j < n; j++) {
        int has = 0;
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) has |= (size_t)a->row_index[p] == j;
        if (!has) return DFM_ERR_STRUCTURALLY_SINGULAR;
    }
    return DFM_OK;
}

/* The factor object with its permutation arrays, and the analysis's O(n) workspace. */
static dfm_result dfm__chol_create(const dfm_csc *a, const dfm_chol_options *opt, const dfm_allocator *al,
                                   dfm_chol **out, dfm__symbolic *s)
{
    dfm_result err = DFM_OK;
    size_t n = a->n_cols;
    dfm_chol *c = (dfm_chol *)dfm__alloc(al, 1, sizeof(dfm_chol), &err);
    *out = NULL;
    memset(s, 0, sizeof *s);
    if (!c) return err;
    memset(c, 0, sizeof *c);
    c->al = *al;
    c->progress = opt->progress;
    c->progress_user = opt->progress_user;
    c->n = n;
    c->nnz_a = a->col_start[n];
    c->pattern_hash = dfm__pattern_hash(a);
    c->failed_column = -1;
    *out = c;
    c->perm = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    c->iperm = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    s->parent = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    s->w1 = (int32_t *)dfm__alloc(al, n + 1, sizeof(int32_t), &err);
    s->w2 = (int32_t *)dfm__alloc(al, n + 1, sizeof(int32_t), &err);
    s->w3 = (int32_t *)dfm__alloc(al, n + 1, sizeof(int32_t), &err);
    s->post = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    s->order = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    s->count = (size_t *)dfm__alloc(al, n, sizeof(size_t), &err);
    return err;
}

/* Step 1a: DFM_ORDER_GIVEN, checked to be a permutation. */
static dfm_result dfm__given_order(size_t n, const int32_t *perm, int32_t *mark, int32_t *order)
{
    size_t j;
    for (j = 0; j < n; j++) mark[j] = 0;
    for (j = 0; j < n; j++) {
        int32_t v = perm[j];
        if (v < 0 || (size_t)v >= n || mark[v]) return DFM_ERR_BAD_INDEX;
        mark[v] = 1;
        order[j] = v;
    }
    return DFM_OK;
}

/* CHOLMOD's test for trying METIS after AMD, on the (block) graph's AMD fill scaled to the
   b x b blocks: nnz(L) >= 5 nnz(A) and flops >= 500 nnz(L). */
static int dfm__try_dissection(const dfm__fill *f, size_t nnz_a, size_t b)
{
    return f->lnz * (double)b * (double)b >= 5.0 * (double)nnz_a && f->flops * (double)b >= 500.0 * f->lnz;
}

/* Step 1b: AMD on the (block) graph; with coordinates and a high AMD fill also nested
   dissection, the one with the smaller fill kept (AMD's own counts when exact, else two symbolic
   counts); the block ordering is expanded to the b unknowns of each block. */
static dfm_result dfm__graph_order(const dfm_csc *a, const dfm_chol_options *opt, const dfm_allocator *al,
                                   dfm__symbolic *s)
{
    size_t b = opt->block_size > 1 ? opt->block_size : 1, nb = a->n_cols / b, k, r;
    size_t *adj_start = NULL;
    int32_t *adj = NULL, *amd = s->post, *nd = s->w3, *cnt_nd = NULL;
    dfm__fill fa = {0.0, 0.0, 0}, fn = {0.0, 0.0, 0};
    dfm_result err = DFM_OK;
    for (k = 0; opt->coords && k < 3 * nb && err == DFM_OK; k++)
        if (!dfm__finite(opt->coords[k])) err = DFM_ERR_BAD_VALUE;
    if (err == DFM_OK) err = dfm__adjacency(a, b, al, &adj_start, &adj);
    if (err == DFM_OK) s->node_count = (int32_t *)dfm__alloc(al, nb, sizeof(int32_t), &err);
    if (err == DFM_OK)
        err = dfm__amd_order((int32_t)nb, adj_start, adj, NULL, al, opt->progress, opt->progress_user, amd, &fa,
                             s->node_count);
    if (err == DFM_OK && opt->coords && nb > DFM__ND_LEAF && dfm__try_dissection(&fa, a->col_start[a->n_cols], b)) {
        cnt_nd = (int32_t *)dfm__alloc(al, nb, sizeof(int32_t), &err);
        if (err == DFM_OK)
            err = dfm__nd_order((int32_t)nb, adj_start, adj, opt->coords, al, opt->progress, opt->progress_user, nd,
                                &fn, cnt_nd);
        if (err == DFM_OK && !(fa.exact && fn.exact)) err = dfm__graph_fill(nb, adj_start, adj, amd, al, &fa.lnz);
        if (err == DFM_OK && !(fa.exact && fn.exact)) err = dfm__graph_fill(nb, adj_start, adj, nd, al, &fn.lnz);
        if (err == DFM_OK && fn.lnz < fa.lnz) {
            int32_t *t = s->node_count;
            memcpy(amd, nd, nb * sizeof(int32_t));
            s->node_count = cnt_nd;
            cnt_nd = t;
            fa = fn;
        }
    }
    if (err == DFM_OK)
        for (k = 0; k < nb; k++)
            for (r = 0; r < b; r++) s->order[k * b + r] = (int32_t)((size_t)amd[k] * b + r);
    if (b > 1 || !fa.exact) { /* counts of the block graph, or inexact with dense rows: not used */
        dfm__free(al, s->node_count);
        s->node_count = NULL;
    }
    dfm__free(al, cnt_nd);
    dfm__free(al, adj_start);
    dfm__free(al, adj);
    return err;
}

/* Step 1: the fill-reducing ordering, into s->order. */
static dfm_result dfm__fill_order(const dfm_csc *a, const dfm_chol_options *opt, const dfm_allocator *al,
                                  dfm__symbolic *s)
{
    size_t j, n = a->n_cols;
    if (opt->ordering == DFM_ORDER_NATURAL) {
        for (j = 0; j < n; j++) s->order[j] = (int32_t)j;
        return DFM_OK;
    }
    if (opt->ordering == DFM_ORDER_GIVEN) return dfm__given_order(n, opt->perm, s->w1, s->order);
    return dfm__graph_order(a, opt, al, s);
}

/* The upper pattern of the matrix permuted by c->iperm, replacing the previous one. */
static dfm_result dfm__permute_pattern(const dfm_csc *a, const dfm_chol *c, const dfm_allocator *al,
                                       dfm__symbolic *s)
{
    dfm__free(al, s->ust);
    dfm__free(al, s->ur);
    s->ust = NULL;
    s->ur = NULL;
    return dfm__permuted_upper(a, c->iperm, al, &s->ust, &s->ur);
}

/* Step 2: elimination tree of the ordered matrix and its postorder, which has the same fill and
   makes every supernode's columns contiguous; c->perm = order composed with the postorder, and
   s->ust/ur/parent describe the matrix in that final numbering. */
static dfm_result dfm__postordered_etree(const dfm_csc *a, dfm_chol *c, const dfm_allocator *al, dfm__symbolic *s)
{
    size_t j, n = c->n;
    dfm_result err;
    for (j = 0; j < n; j++) c->iperm[s->order[j]] = (int32_t)j;
    err = dfm__permute_pattern(a, c, al, s);
    if (err != DFM_OK) return err;
    dfm__etree(n, s->ust, s->ur, s->parent, s->w1);
    dfm__postorder(n, s->parent, s->w1, s->w2, s->w3, s->post);
    for (j = 0; j < n; j++) c->perm[j] = s->order[s->post[j]];
    for (j = 0; j < n; j++) c->iperm[c->perm[j]] = (int32_t)j;
    /* the etree of the postordered matrix is the same tree relabelled: a postorder keeps each
       column's ancestors, which hold its structure, in their order */
    for (j = 0; j < n; j++) s->w1[s->post[j]] = (int32_t)j;
    for (j = 0; j < n; j++) s->w2[j] = s->parent[s->post[j]] < 0 ? -1 : s->w1[s->parent[s->post[j]]];
    memcpy(s->parent, s->w2, n * sizeof(int32_t));
    return DFM_OK;
}

/* Step 3: column counts: the ones AMD counted when exact (s->node_count), else by row subtrees
   (row r of L holds the etree nodes on the paths from each upper entry (k, r) up to r, on the
   pattern in the final numbering). Also nnz(L) and the flop count. */
static dfm_result dfm__column_counts(const dfm_csc *a, dfm_chol *c, const dfm_allocator *al, dfm__symbolic *s)
{
    size_t j, p, n = c->n;
    int32_t *mark = s->w1;
    dfm_result err = DFM_OK;
    if (s->node_count)
        for (j = 0; j < n; j++) s->count[j] = (size_t)s->node_count[c->perm[j]];
    else
        err = dfm__permute_pattern(a, c, al, s);
    if (err != DFM_OK) return err;
    for (j = 0; j < n && !s->node_count; j++) {
        s->count[j] = 1;
        mark[j] = -1;
    }
    for (j = 0; j < n && !s->node_count; j++) {
        mark[j] = (int32_t)j;
        for (p = s->ust[j]; p < s->ust[j + 1]; p++) {
            int32_t x = s->ur[p];
            while (mark[x] != (int32_t)j) {
                s->count[x]++;
                mark[x] = (int32_t)j;
                x = s->parent[x];
            }
        }
    }
    c->nnz_l = 0;
    c->flops = 0.0;
    for (j = 0; j < n; j++) {
        c->nnz_l += s->count[j];
        c->flops += (double)s->count[j] * (double)s->count[j];
    }
    return DFM_OK;
}

/* Step 4: fundamental supernodes: j + 1 joins j when it is j's parent, its only child, and its
   column is j's minus the diagonal. */
static dfm_result dfm__fundamental_supernodes(size_t n, const dfm_allocator *al, dfm__symbolic *s)
{
    dfm_result err = DFM_OK;
    size_t j;
    int32_t *nchild = s->w2;
    for (j = 0; j < n; j++) nchild[j] = 0;
    for (j = 0; j < n; j++)
        if (s->parent[j] != -1) nchild[s->parent[j]]++;
    s->fstart = (size_t *)dfm__alloc(al, n + 1, sizeof(size_t), &err);
    s->gcols = (size_t *)dfm__alloc(al, n + 1, sizeof(size_t), &err);
    s->grows = (size_t *)dfm__alloc(al, n + 1, sizeof(size_t), &err);
    s->gzeros = (size_t *)dfm__alloc(al, n + 1, sizeof(size_t), &err);
    s->gnext = (size_t *)dfm__alloc(al, n + 1, sizeof(size_t), &err);
    if (err != DFM_OK) return err;
    s->nf = 0;
    for (j = 0; j < n; j++) {
        if (j > 0 && s->parent[j - 1] == (int32_t)j && nchild[j] == 1 && s->count[j] + 1 == s->count[j - 1]) continue;
        s->fstart[s->nf++] = j;
    }
    s->fstart[s->nf] = n;
    return DFM_OK;
}

/* Step 5: relaxed amalgamation, from the last supernode down: s joins the group after it when
   that group holds s's parent and the merged block stays small or dense enough. */
static void dfm__relax_supernodes(dfm__symbolic *s)
{
    size_t g, nf = s->nf;
    for (g = 0; g < nf; g++) {
        s->gcols[g] = s->fstart[g + 1] - s->fstart[g];
        s->grows[g] = s->count[s->fstart[g]];
        s->gzeros[g] = 0;
        s->gnext[g] = g + 1;
    }
    for (g = nf - 1; g-- > 0;) {
        size_t last = s->fstart[g + 1] - 1, nc, nr, ent, z;
        if (s->parent[last] != (int32_t)(last + 1)) continue;
        nc = s->gcols[g] + s->gcols[g + 1];
        nr = s->gcols[g] + s->grows[g + 1];
        ent = dfm__trapezoid(nc, nr);
        z = s->gzeros[g] + s->gzeros[g + 1] + ent - dfm__trapezoid(s->gcols[g], s->grows[g]) -
            dfm__trapezoid(s->gcols[g + 1], s->grows[g + 1]);
        if (!dfm__relax_merge(nc, ent, z)) continue;
        s->gcols[g] = nc;
        s->grows[g] = nr;
        s->gzeros[g] = z;
        s->gnext[g] = s->gnext[g + 1];
        s->gcols[g + 1] = 0; /* no longer a group head */
    }
}

/* Step 6: the supernode partition (the group heads) and the offsets of each supernode's rows and
   values. */
static dfm_result dfm__supernode_layout(dfm_chol *c, const dfm_allocator *al, const dfm__symbolic *s)
{
    dfm_result err = DFM_OK;
    size_t g, j, ns = 0, total_rows = 0, total_vals = 0, big = (size_t)-1 >> 4;
    for (g = 0; g < s->nf; g = s->gnext[g]) ns++;
    c->nsuper = ns;
    c->sup_first = (int32_t *)dfm__alloc(al, ns + 1, sizeof(int32_t), &err);
    c->sup_rowptr = (size_t *)dfm__alloc(al, ns + 1, sizeof(size_t), &err);
    c->sup_valptr = (size_t *)dfm__alloc(al, ns + 1, sizeof(size_t), &err);
    c->col_super = (int32_t *)dfm__alloc(al, c->n, sizeof(int32_t), &err);
    if (err != DFM_OK) return err;
    ns = 0;
    for (g = 0; g < s->nf; g = s->gnext[g]) {
        c->sup_first[ns] = (int32_t)s->fstart[g];
        c->sup_rowptr[ns] = total_rows;
        c->sup_valptr[ns] = total_vals;
        if (s->grows[g] > big / s->gcols[g] || total_vals > big - s->grows[g] * s->gcols[g]) return DFM_ERR_TOO_LARGE;
        total_rows += s->grows[g];
        total_vals += s->grows[g] * s->gcols[g];
        for (j = s->fstart[g]; j < s->fstart[g] + s->gcols[g]; j++) c->col_super[j] = (int32_t)ns;
        ns++;
    }
    c->sup_first[ns] = (int32_t)c->n;
    c->sup_rowptr[ns] = total_rows;
    c->sup_valptr[ns] = total_vals;
    return DFM_OK;
}

/* Step 7: A's entries grouped by new column (the smaller of the two new indices): where each
   comes from (c->amap_src) and its new row (s->arow); c->amap_dst is filled by step 8. */
static dfm_result dfm__map_entries(dfm_chol *c, const dfm_csc *a, const dfm_allocator *al, dfm__symbolic *s)
{
    dfm_result err = DFM_OK;
    size_t n = c->n, j, p;
    c->rows = (int32_t *)dfm__alloc(al, c->sup_rowptr[c->nsuper], sizeof(int32_t), &err);
    s->relmap = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    s->buf = (int32_t *)dfm__alloc(al, n, sizeof(int32_t), &err);
    s->arow = (int32_t *)dfm__alloc(al, c->nnz_a, sizeof(int32_t), &err);
    c->amap_start = (size_t *)dfm__alloc(al, n + 2, sizeof(size_t), &err);
    c->amap_src = (size_t *)dfm__alloc(al, c->nnz_a, sizeof(size_t), &err);
    c->amap_dst = (size_t *)dfm__alloc(al, c->nnz_a, sizeof(size_t), &err);
    if (err != DFM_OK) return err;
    memset(c->amap_start, 0, (n + 2) * sizeof(size_t));
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            int32_t I = c->iperm[a->row_index[p]], J = c->iperm[j];
            c->amap_start[(I < J ? I : J) + 2]++;
        }
    for (j = 0; j < n; j++) c->amap_start[j + 2] += c->amap_start[j + 1];
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            int32_t I = c->iperm[a->row_index[p]], J = c->iperm[j];
            size_t t = c->amap_start[(I < J ? I : J) + 1]++;
            c->amap_src[t] = p;
            s->arow[t] = I > J ? I : J;
        }
    return DFM_OK;
}

/* The rows of supernode sn into s->buf, unsorted: its columns, then the rows below them of A's
   columns and of its children's rows (children come first in postorder; s->w2 = head and s->w3 =
   next of the children lists, s->w1 = marks). Returns the count. */
static size_t dfm__gather_rows(const dfm_chol *c, size_t sn, dfm__symbolic *s)
{
    size_t f = (size_t)c->sup_first[sn], l = (size_t)c->sup_first[sn + 1], cnt = 0, j, t;
    int32_t ch, *mark = s->w1;
    for (j = f; j < l; j++) {
        s->buf[cnt++] = (int32_t)j;
        mark[j] = (int32_t)sn;
    }
    for (j = f; j < l; j++)
        for (t = c->amap_start[j]; t < c->amap_start[j + 1]; t++) {
            int32_t row = s->arow[t];
            if (mark[row] != (int32_t)sn) {
                mark[row] = (int32_t)sn;
                s->buf[cnt++] = row;
            }
        }
    for (ch = s->w2[sn]; ch != -1; ch = s->w3[ch]) {
        size_t cnc = (size_t)(c->sup_first[ch + 1] - c->sup_first[ch]);
        for (t = c->sup_rowptr[ch] + cnc; t < c->sup_rowptr[ch + 1]; t++) {
            int32_t row = c->rows[t];
            if ((size_t)row >= f && mark[row] != (int32_t)sn) {
                mark[row] = (int32_t)sn;
                s->buf[cnt++] = row;
            }
        }
    }
    return cnt;
}

/* Step 8: each supernode's sorted row structure, where A's entries land in its value block
   (c->amap_dst), the parent supernode's children list, and the largest update block. */
static dfm_result dfm__supernode_rows(dfm_chol *c, const dfm_chol_options *opt, dfm__symbolic *s)
{
    size_t sn, j, t, r, n = c->n, ns = c->nsuper;
    for (j = 0; j < n; j++) {
        s->relmap[j] = -1;
        s->w1[j] = -1;
    }
    for (sn = 0; sn < ns; sn++) s->w2[sn] = -1;
    c->max_update = 1;
    for (sn = 0; sn < ns; sn++) {
        size_t f = (size_t)c->sup_first[sn], l = (size_t)c->sup_first[sn + 1], nc = l - f;
        size_t cnt = dfm__gather_rows(c, sn, s);
        int32_t *rs = c->rows + c->sup_rowptr[sn];
        if (cnt != c->sup_rowptr[sn + 1] - c->sup_rowptr[sn]) return DFM_ERR_INVALID_ARGUMENT; /* cannot happen */
        dfm__sort_rows(s->buf + nc, cnt - nc);
        memcpy(rs, s->buf, cnt * sizeof(int32_t));
        if (cnt > c->max_rows) c->max_rows = cnt;
        for (r = 0; r < cnt; r++) s->relmap[rs[r]] = (int32_t)r;
        for (j = f; j < l; j++)
            for (t = c->amap_start[j]; t < c->amap_start[j + 1]; t++)
                c->amap_dst[t] = c->sup_valptr[sn] + (j - f) * cnt + (size_t)s->relmap[s->arow[t]];
        if (cnt > nc) {
            int32_t ps = c->col_super[rs[nc]];
            size_t m = cnt - nc;
            s->w3[sn] = s->w2[ps];
            s->w2[ps] = (int32_t)sn;
            if (m * m > c->max_update) c->max_update = m * m;
        }
        if (opt->progress && (sn & 4095) == 0 &&
            opt->progress(opt->progress_user, 0.9f + 0.1f * (float)sn / (float)ns))
            return DFM_CANCELLED;
    }
    return DFM_OK;
}

/* The symbolic analysis as CSparse's cs_schol and CHOLMOD's analysis do it, step by step. */
DFMDEF dfm_result dfm_chol_analyze(const dfm_csc *a, const dfm_chol_options *options, dfm_chol **out)
{
    dfm_chol_options opt = options ? *options : dfm_chol_default_options();
    dfm_allocator al = dfm__resolve_allocator(opt.allocator);
    dfm__symbolic s;
    dfm_chol *c = NULL;
    dfm_result err;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    *out = NULL;
    err = dfm__analyze_check(a, &opt);
    if (err != DFM_OK) return err;
    err = dfm__chol_create(a, &opt, &al, &c, &s);
    if (err == DFM_OK) err = dfm__fill_order(a, &opt, &al, &s);       /* 1. AMD / ND / given */
    if (err == DFM_OK) err = dfm__postordered_etree(a, c, &al, &s);   /* 2. etree, postorder */
    if (err == DFM_OK) err = dfm__column_counts(a, c, &al, &s);       /* 3. column counts */
    if (err == DFM_OK) err = dfm__fundamental_supernodes(c->n, &al, &s); /* 4. supernodes */
    if (err == DFM_OK) dfm__relax_supernodes(&s);                     /* 5. amalgamation */
    if (err == DFM_OK) err = dfm__supernode_layout(c, &al, &s);       /* 6. partition */
    if (err == DFM_OK) err = dfm__map_entries(c, a, &al, &s);         /* 7. A's entries */
    if (err == DFM_OK) err = dfm__supernode_rows(c, &opt, &s);        /* 8. row structure */
    if (err == DFM_OK) c->values = (double *)dfm__alloc(&al, c->sup_valptr[c->nsuper], sizeof(double), &err);
    if (err == DFM_OK) {
        c->colcount = s.count;
        s.count = NULL;
        if (opt.progress && opt.progress(opt.progress_user, 1.0f)) err = DFM_CANCELLED;
    }
    dfm__symbolic_free(&s, &al);
    if (err != DFM_OK) dfm_chol_free(c);
    else *out = c;
    return err;
}

/* ---------------------------------------------------------------------------------------------
   Section: dense kernels (column-major)
   --------------------------------------------------------------------------------------------- */

/* Two-lane double vectors through the GCC/Clang vector extension (SSE2 on x86-64, NEON on
   arm64); plain C elsewhere or with DFM_NO_VECTOR_EXTENSIONS. Loads and stores go through memcpy,
   so no alignment is assumed. */
#if (defined(__GNUC__) || defined(__clang__)) && !defined(DFM_NO_VECTOR_EXTENSIONS)
#define DFM__V2 1
typedef double dfm__v2 __attribute__((vector_size(16)));
static inline dfm__v2 dfm__ld2(const double *p)
{
    dfm__v2 v;
    memcpy(&v, p, sizeof v);
    return v;
}
static inline void dfm__st2(double *p, dfm__v2 v) { memcpy(p, &v, sizeof v); }
#endif

/* C (m x k) -= A (m x p) B (k x p)^T, or C = -A B^T when assign is set (C need not be
   initialized), in 4 x 4 register tiles. */
static void dfm__gemm_nt(size_t m, size_t k, size_t p, const double *A, size_t lda, const double *B, size_t ldb,
                         double *C, size_t ldc, int assign)
{
    size_t i, j, t;
    for (j = 0; j + 4 <= k; j += 4) {
        for (i = 0; i + 4 <= m; i += 4) {
            const double *a = A + i, *bb = B + j;
            double *c0 = C + i + j * ldc, *c1 = c0 + ldc, *c2 = c1 + ldc, *c3 = c2 + ldc;
#ifdef DFM__V2
            dfm__v2 z = {0.0, 0.0}, x0 = z, y0 = z, x1 = z, y1 = z, x2 = z, y2 = z, x3 = z, y3 = z;
            for (t = 0; t < p; t++, a += lda, bb += ldb) {
                dfm__v2 lo = dfm__ld2(a), hi = dfm__ld2(a + 2);
                dfm__v2 b0 = {bb[0], bb[0]}, b1 = {bb[1], bb[1]}, b2 = {bb[2], bb[2]}, b3 = {bb[3], bb[3]};
                x0 += lo * b0; y0 += hi * b0;
                x1 += lo * b1; y1 += hi * b1;
                x2 += lo * b2; y2 += hi * b2;
                x3 += lo * b3; y3 += hi * b3;
            }
            if (assign) {
                dfm__st2(c0, -x0); dfm__st2(c0 + 2, -y0);
                dfm__st2(c1, -x1); dfm__st2(c1 + 2, -y1);
                dfm__st2(c2, -x2); dfm__st2(c2 + 2, -y2);
                dfm__st2(c3, -x3); dfm__st2(c3 + 2, -y3);
            } else {
                dfm__st2(c0, dfm__ld2(c0) - x0); dfm__st2(c0 + 2, dfm__ld2(c0 + 2) - y0);
                dfm__st2(c1, dfm__ld2(c1) - x1); dfm__st2(c1 + 2, dfm__ld2(c1 + 2) - y1);
                dfm__st2(c2, dfm__ld2(c2) - x2); dfm__st2(c2 + 2, dfm__ld2(c2 + 2) - y2);
                dfm__st2(c3, dfm__ld2(c3) - x3); dfm__st2(c3 + 2, dfm__ld2(c3 + 2) - y3);
            }
#else
            double c00 = 0, c10 = 0, c20 = 0, c30 = 0, c01 = 0, c11 = 0, c21 = 0, c31 = 0;
            double c02 = 0, c12 = 0, c22 = 0, c32 = 0, c03 = 0, c13 = 0, c23 = 0, c33 = 0;
            for (t = 0; t < p; t++, a += lda, bb += ldb) {
                double a0 = a[0], a1 = a[1], a2 = a[2], a3 = a[3];
                double b0 = bb[0], b1 = bb[1], b2 = bb[2], b3 = bb[3];
                c00 += a0 * b0; c10 += a1 * b0; c20 += a2 * b0; c30 += a3 * b0;
                c01 += a0 * b1; c11 += a1 * b1; c21 += a2 * b1; c31 += a3 * b1;
                c02 += a0 * b2; c12 += a1 * b2; c22 += a2 * b2; c32 += a3 * b2;
                c03 += a0 * b3; c13 += a1 * b3; c23 += a2 * b3; c33 += a3 * b3;
            }
            if (assign) { /* -sum, as the vector tiles store it (0.0 - sum differs at zero) */
                c0[0] = -c00; c0[1] = -c10; c0[2] = -c20; c0[3] = -c30;
                c1[0] = -c01; c1[1] = -c11; c1[2] = -c21; c1[3] = -c31;
                c2[0] = -c02; c2[1] = -c12; c2[2] = -c22; c2[3] = -c32;
                c3[0] = -c03; c3[1] = -c13; c3[2] = -c23; c3[3] = -c33;
            } else {
                c0[0] -= c00; c0[1] -= c10; c0[2] -= c20; c0[3] -= c30;
                c1[0] -= c01; c1[1] -= c11; c1[2] -= c21; c1[3] -= c31;
                c2[0] -= c02; c2[1] -= c12; c2[2] -= c22; c2[3] -= c32;
                c3[0] -= c03; c3[1] -= c13; c3[2] -= c23; c3[3] -= c33;
            }
#endif
        }
        for (; i < m; i++) {
            double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
            const double *a = A + i, *bb = B + j;
            for (t = 0; t < p; t++, a += lda, bb += ldb) {
                s0 += a[0] * bb[0];
                s1 += a[0] * bb[1];
                s2 += a[0] * bb[2];
                s3 += a[0] * bb[3];
            }
            if (assign) {
                C[i + j * ldc] = -s0;
                C[i + (j + 1) * ldc] = -s1;
                C[i + (j + 2) * ldc] = -s2;
                C[i + (j + 3) * ldc] = -s3;
            } else {
                C[i + j * ldc] -= s0;
                C[i + (j + 1) * ldc] -= s1;
                C[i + (j + 2) * ldc] -= s2;
                C[i + (j + 3) * ldc] -= s3;
            }
        }
    }
    for (; j < k; j++) {
        double *cj = C + j * ldc;
        if (assign)
            for (i = 0; i < m; i++) cj[i] = 0.0;
        for (t = 0; t < p; t++) {
            double bj = B[j + t * ldb];
            const double *a = A + t * lda;
            for (i = 0; i < m; i++) cj[i] -= a[i] * bj;
        }
    }
}

/* Runtime dispatch to an AVX version of the gemm tile on x86 (compiled for AVX through a target
   attribute, chosen by the CPU's feature bits; DFM_NO_RUNTIME_DISPATCH turns it off). It
   computes each entry with the same operations in the same order as the two-lane tile (no FMA),
   so the factor has the same bits with and without AVX. */
#if defined(DFM__V2) && (defined(__x86_64__) || defined(__i386__)) && !defined(DFM_NO_RUNTIME_DISPATCH) && \
    (defined(__clang__) || (defined(__GNUC__) && __GNUC__ >= 6))
#define DFM__AVX 1
typedef double dfm__v4 __attribute__((vector_size(32)));
#ifndef DFM__GEMM_L2
#define DFM__GEMM_L2 32768 /* doubles of B kept in L2 by the gemm tile's column chunks (256 KiB) */
#endif

/* C (m x k) -= A B^T for m a multiple of 8 and k a multiple of 4, in 8 x 4 tiles. The columns
   of C go in chunks whose rows of B (jc x p) stay in L2, and each strip of 8 rows of A stays in
   L1 across the chunk's tiles, so A is read from memory once a chunk instead of once per 4
   columns. Every tile still sums its full inner dimension in order: the bits do not depend on
   the chunking. Row i of C is row i0 + i of the caller's (for skipping tiles above the diagonal
   with assign). */
__attribute__((target("avx"))) static void dfm__gemm_nt_avx(size_t m, size_t k, size_t p, const double *A, size_t lda,
                                                              const double *B, size_t ldb, double *C, size_t ldc,
                                                              int assign, size_t i0)
{
    size_t i, j, t, q, j0, jc = p > 0 ? (DFM__GEMM_L2 / p) & ~(size_t)3 : k;
    if (jc < 4) jc = 4;
    for (j0 = 0; j0 < k; j0 += jc) {
        size_t j1 = k - j0 < jc ? k : j0 + jc;
        for (i = 0; i < m; i += 8)
            for (j = j0; j < j1; j += 4) {
                const double *a = A + i, *bb = B + j;
                if (assign && i0 + i + 8 <= j) continue; /* above the diagonal (dfm__gemm) */
                dfm__v4 z = {0.0, 0.0, 0.0, 0.0}, acc[8];
                for (q = 0; q < 8; q++) acc[q] = z;
                for (t = 0; t < p; t++, a += lda, bb += ldb) {
                    dfm__v4 lo, hi, b0 = {bb[0], bb[0], bb[0], bb[0]}, b1 = {bb[1], bb[1], bb[1], bb[1]};
                    dfm__v4 b2 = {bb[2], bb[2], bb[2], bb[2]}, b3 = {bb[3], bb[3], bb[3], bb[3]};
                    memcpy(&lo, a, sizeof lo);
                    memcpy(&hi, a + 4, sizeof hi);
                    acc[0] += lo * b0; acc[1] += hi * b0;
                    acc[2] += lo * b1; acc[3] += hi * b1;
                    acc[4] += lo * b2; acc[5] += hi * b2;
                    acc[6] += lo * b3; acc[7] += hi * b3;
                }
                for (q = 0; q < 4; q++) {
                    double *cq = C + i + (j + q) * ldc;
                    dfm__v4 c0, c1;
                    if (assign) {
                        c0 = -acc[2 * q];
                        c1 = -acc[2 * q + 1];
                    } else {
                        memcpy(&c0, cq, sizeof c0);
                        memcpy(&c1, cq + 4, sizeof c1);
                        c0 -= acc[2 * q];
                        c1 -= acc[2 * q + 1];
                    }
                    memcpy(cq, &c0, sizeof c0);
                    memcpy(cq + 4, &c1, sizeof c1);
                }
            }
    }
}

/* The last k % 4 (< 4) columns of C -= A B^T (C = -A B^T with assign) in strips of 16 rows,
   one column at a time: each entry has its products subtracted one by one in order, as the
   plain remainder loop does (same bits). Returns the rows done (a multiple of 16). */
__attribute__((target("avx"))) static size_t dfm__gemm_cols_avx(size_t m, size_t kr, size_t p, const double *A,
                                                                size_t lda, const double *B, size_t ldb, double *C,
                                                                size_t ldc, int assign)
{
    size_t i, t, q;
    for (i = 0; i + 16 <= m; i += 16)
        for (q = 0; q < kr; q++) {
            double *cq = C + i + q * ldc;
            dfm__v4 z = {0.0, 0.0, 0.0, 0.0}, c0 = z, c1 = z, c2 = z, c3 = z;
            const double *a = A + i;
            if (!assign) {
                memcpy(&c0, cq, sizeof c0);
                memcpy(&c1, cq + 4, sizeof c1);
                memcpy(&c2, cq + 8, sizeof c2);
                memcpy(&c3, cq + 12, sizeof c3);
            }
            for (t = 0; t < p; t++, a += lda) {
                dfm__v4 b = z + B[q + t * ldb], a0, a1, a2, a3;
                memcpy(&a0, a, sizeof a0);
                memcpy(&a1, a + 4, sizeof a1);
                memcpy(&a2, a + 8, sizeof a2);
                memcpy(&a3, a + 12, sizeof a3);
                c0 -= a0 * b; c1 -= a1 * b; c2 -= a2 * b; c3 -= a3 * b;
            }
            memcpy(cq, &c0, sizeof c0);
            memcpy(cq + 4, &c1, sizeof c1);
            memcpy(cq + 8, &c2, sizeof c2);
            memcpy(cq + 12, &c3, sizeof c3);
        }
    return i;
}

/* The same tile on 16 rows with AVX-512F (8 lanes): each entry gets the same operations in the
   same order as in the 8 x 4 tile (no FMA), so the bits do not change; twice the arithmetic per
   instruction. */
#if !defined(DFM_NO_AVX512)
#define DFM__AVX512 1
typedef double dfm__v8 __attribute__((vector_size(64)));
/* AVX-512F has FMA instructions: the contraction pragmas at the top of the implementation keep
   a * b + c in two roundings here too.
   One 16 x 4 tile over the whole inner dimension: a steps by astep, b by bstep per t */
__attribute__((target("avx512f"))) static inline void dfm__tile16x4_avx512(
    size_t p, const double *a, size_t astep, const double *bb, size_t bstep, double *C, size_t ldc, int assign)
{
    size_t t, q;
    dfm__v8 z = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, acc[8];
    for (q = 0; q < 8; q++) acc[q] = z;
    for (t = 0; t < p; t++, a += astep, bb += bstep) {
        dfm__v8 lo, hi, b0 = z + bb[0], b1 = z + bb[1], b2 = z + bb[2], b3 = z + bb[3];
        memcpy(&lo, a, sizeof lo);
        memcpy(&hi, a + 8, sizeof hi);
        acc[0] += lo * b0; acc[1] += hi * b0;
        acc[2] += lo * b1; acc[3] += hi * b1;
        acc[4] += lo * b2; acc[5] += hi * b2;
        acc[6] += lo * b3; acc[7] += hi * b3;
    }
    for (q = 0; q < 4; q++) {
        double *cq = C + q * ldc;
        dfm__v8 c0, c1;
        if (assign) {
            c0 = -acc[2 * q];
            c1 = -acc[2 * q + 1];
        } else {
            memcpy(&c0, cq, sizeof c0);
            memcpy(&c1, cq + 8, sizeof c1);
            c0 -= acc[2 * q];
            c1 -= acc[2 * q + 1];
        }
        memcpy(cq, &c0, sizeof c0);
        memcpy(cq + 8, &c1, sizeof c1);
    }
}

/* C (m x k) -= A B^T for m a multiple of 16 and k of 4. With a workspace (ws, at least
   dfm__gemm_ws(p) doubles) and enough reuse, each chunk of B and each strip of A is first
   copied into contiguous tile order (packing, as BLAS does), so the tiles stream unit-stride
   memory whatever the leading dimensions; the sums are the same either way. */
__attribute__((target("avx512f"))) static void dfm__gemm_nt_avx512(size_t m, size_t k, size_t p, const double *A,
                                                                   size_t lda, const double *B, size_t ldb,
                                                                   double *C, size_t ldc, int assign, double *ws)
{
    size_t i, j, t, q, j0, jc = p > 0 ? (DFM__GEMM_L2 / p) & ~(size_t)3 : k;
    int pack = ws != NULL && m >= 64 && k >= 8 && p >= 8;
    if (jc < 4) jc = 4;
    for (j0 = 0; j0 < k; j0 += jc) {
        size_t j1 = k - j0 < jc ? k : j0 + jc;
        double *bp = ws, *ap = ws + (j1 - j0) * p;
        if (pack)
            for (j = j0; j < j1; j += 4)
                for (t = 0; t < p; t++)
                    for (q = 0; q < 4; q++) bp[(j - j0) * p + 4 * t + q] = B[j + q + t * ldb];
        for (i = 0; i < m; i += 16) {
            int pack_a = pack && j1 - j0 >= 32;
            if (pack_a)
                for (t = 0; t < p; t++) memcpy(ap + 16 * t, A + i + t * lda, 16 * sizeof(double));
            for (j = j0; j < j1; j += 4) {
                if (assign && i + 16 <= j) continue; /* above the diagonal: not needed (dfm__gemm) */
                if (pack) dfm__tile16x4_avx512(p, pack_a ? ap : A + i, pack_a ? 16 : lda, bp + (j - j0) * p, 4,
                                               C + i + j * ldc, ldc, assign);
                else dfm__tile16x4_avx512(p, A + i, lda, B + j, ldb, C + i + j * ldc, ldc, assign);
            }
        }
    }
}
#endif
#endif

/* C (m x k) -= A B^T, or C = -A B^T with assign: then only the entries on and below the diagonal
   (row >= column) are the product's, those above may be left unset. With the AVX-512 / AVX tiles
   where the CPU has them. */
static void dfm__gemm(size_t m, size_t k, size_t p, const double *A, size_t lda, const double *B, size_t ldb,
                      double *C, size_t ldc, int assign, double *ws)
{
#ifdef DFM__AVX
    size_t m8 = m & ~(size_t)7, k4 = k & ~(size_t)3, m16 = 0, i0;
    if (m8 > 0 && __builtin_cpu_supports("avx")) {
#ifdef DFM__AVX512
        if (m >= 16 && k4 > 0 && __builtin_cpu_supports("avx512f")) {
            m16 = m & ~(size_t)15;
            dfm__gemm_nt_avx512(m16, k4, p, A, lda, B, ldb, C, ldc, assign, ws);
        }
#endif
        if (m8 > m16 && k4 > 0) dfm__gemm_nt_avx(m8 - m16, k4, p, A + m16, lda, B, ldb, C + m16, ldc, assign, m16);
        if (m > m8 && k4 > 0) dfm__gemm_nt(m - m8, k4, p, A + m8, lda, B, ldb, C + m8, ldc, assign);
        if (k > k4) {
            i0 = dfm__gemm_cols_avx(m, k - k4, p, A, lda, B + k4, ldb, C + k4 * ldc, ldc, assign);
            if (m > i0) dfm__gemm_nt(m - i0, k - k4, p, A + i0, lda, B + k4, ldb, C + i0 + k4 * ldc, ldc, assign);
        }
        return;
    }
#endif
    (void)ws;
    dfm__gemm_nt(m, k, p, A, lda, B, ldb, C, ldc, assign);
}

/* doubles of gemm workspace for an inner dimension up to p (0: the kernels need none) */
static size_t dfm__gemm_ws(size_t p)
{
#ifdef DFM__AVX512
    return DFM__GEMM_L2 + 20 * p;
#else
    (void)p;
    return 0;
#endif
}

/* The rows below a factored jb x jb diagonal block D: X (m x jb) <- X D^-T, in tiles of rows.
   Each entry gets the column loop's operations in its order (x -= X[r,t] D[c,t] for t = 0 .. c-1,
   one rounding each, then x *= 1 / D[c,c]), so a tile size or vector width gives the same bits
   as one row at a time; a tile's rows stay in registers while D's rows stream from L1. */
#ifdef DFM__AVX
__attribute__((target("avx"))) static size_t dfm__trsm_rows_avx(size_t m, size_t jb, const double *D, double *X,
                                                                 size_t ld)
{
    size_t i, c, t;
    for (i = 0; i + 16 <= m; i += 16)
        for (c = 0; c < jb; c++) {
            double *xc = X + i + c * ld;
            double s = 1.0 / D[c + c * ld];
            dfm__v4 v0, v1, v2, v3, inv = {s, s, s, s};
            memcpy(&v0, xc, sizeof v0);
            memcpy(&v1, xc + 4, sizeof v1);
            memcpy(&v2, xc + 8, sizeof v2);
            memcpy(&v3, xc + 12, sizeof v3);
            for (t = 0; t < c; t++) {
                const double *xt = X + i + t * ld;
                double f = D[c + t * ld];
                dfm__v4 b = {f, f, f, f}, a0, a1, a2, a3;
                memcpy(&a0, xt, sizeof a0);
                memcpy(&a1, xt + 4, sizeof a1);
                memcpy(&a2, xt + 8, sizeof a2);
                memcpy(&a3, xt + 12, sizeof a3);
                v0 -= a0 * b; v1 -= a1 * b; v2 -= a2 * b; v3 -= a3 * b;
            }
            v0 *= inv; v1 *= inv; v2 *= inv; v3 *= inv;
            memcpy(xc, &v0, sizeof v0);
            memcpy(xc + 4, &v1, sizeof v1);
            memcpy(xc + 8, &v2, sizeof v2);
            memcpy(xc + 12, &v3, sizeof v3);
        }
    return i;
}
#endif

#ifdef DFM__AVX512
/* the same on strips of 32 rows, four 8-lane vectors */
__attribute__((target("avx512f"))) static size_t dfm__trsm_rows_avx512(size_t m, size_t jb, const double *D,
                                                                       double *X, size_t ld)
{
    size_t i, c, t;
    for (i = 0; i + 32 <= m; i += 32)
        for (c = 0; c < jb; c++) {
            double *xc = X + i + c * ld;
            dfm__v8 z = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, v0, v1, v2, v3, inv = z + 1.0 / D[c + c * ld];
            memcpy(&v0, xc, sizeof v0);
            memcpy(&v1, xc + 8, sizeof v1);
            memcpy(&v2, xc + 16, sizeof v2);
            memcpy(&v3, xc + 24, sizeof v3);
            for (t = 0; t < c; t++) {
                const double *xt = X + i + t * ld;
                dfm__v8 b = z + D[c + t * ld], a0, a1, a2, a3;
                memcpy(&a0, xt, sizeof a0);
                memcpy(&a1, xt + 8, sizeof a1);
                memcpy(&a2, xt + 16, sizeof a2);
                memcpy(&a3, xt + 24, sizeof a3);
                v0 -= a0 * b; v1 -= a1 * b; v2 -= a2 * b; v3 -= a3 * b;
            }
            v0 *= inv; v1 *= inv; v2 *= inv; v3 *= inv;
            memcpy(xc, &v0, sizeof v0);
            memcpy(xc + 8, &v1, sizeof v1);
            memcpy(xc + 16, &v2, sizeof v2);
            memcpy(xc + 24, &v3, sizeof v3);
        }
    return i;
}
#endif

static void dfm__trsm_rows(size_t m, size_t jb, const double *D, double *X, size_t ld)
{
    size_t i = 0, c, t;
#ifdef DFM__AVX512
    if (m >= 32 && __builtin_cpu_supports("avx512f")) i = dfm__trsm_rows_avx512(m, jb, D, X, ld);
#endif
#ifdef DFM__AVX
    if (m - i >= 16 && __builtin_cpu_supports("avx")) i += dfm__trsm_rows_avx(m - i, jb, D, X + i, ld);
#endif
#ifdef DFM__V2
    for (; i + 8 <= m; i += 8)
        for (c = 0; c < jb; c++) {
            double *xc = X + i + c * ld, s = 1.0 / D[c + c * ld];
            dfm__v2 v0 = dfm__ld2(xc), v1 = dfm__ld2(xc + 2), v2 = dfm__ld2(xc + 4), v3 = dfm__ld2(xc + 6), inv = {s, s};
            for (t = 0; t < c; t++) {
                const double *xt = X + i + t * ld;
                dfm__v2 b = {D[c + t * ld], D[c + t * ld]};
                v0 -= dfm__ld2(xt) * b; v1 -= dfm__ld2(xt + 2) * b;
                v2 -= dfm__ld2(xt + 4) * b; v3 -= dfm__ld2(xt + 6) * b;
            }
            dfm__st2(xc, v0 * inv); dfm__st2(xc + 2, v1 * inv);
            dfm__st2(xc + 4, v2 * inv); dfm__st2(xc + 6, v3 * inv);
        }
#endif
    for (; i < m; i++)
        for (c = 0; c < jb; c++) {
            double x = X[i + c * ld];
            for (t = 0; t < c; t++) x -= X[i + t * ld] * D[c + t * ld];
            X[i + c * ld] = x * (1.0 / D[c + c * ld]);
        }
}

/* Cholesky of the nc leading columns of an nr x nc panel (ld >= nr): the top nc x nc block
   becomes L11 (lower), the rows below become L21 = A21 L11^-T. Returns -1 on success or the
   failing column. Blocked left-looking: each block of columns is updated by the ones before it
   with the gemm kernel, its diagonal block factored column by column, then the rows below it
   solved in row tiles (dfm__trsm_rows: the same operations per entry as the column loop). */
static long dfm__panel_chol(size_t nr, size_t nc, double *L, size_t ld, double *ws)
{
    const size_t NB = 48;
    size_t j0, c, t, r;
    for (j0 = 0; j0 < nc; j0 += NB) {
        size_t jb = nc - j0 < NB ? nc - j0 : NB, end = j0 + jb;
        if (j0 > 0) dfm__gemm(nr - j0, jb, j0, L + j0, ld, L + j0, ld, L + j0 + j0 * ld, ld, 0, ws);
        for (c = j0; c < end; c++) {
            double *lc = L + c * ld, d, inv;
            for (t = j0; t < c; t++) {
                const double *lt = L + t * ld;
                double f = lt[c];
                for (r = c; r < end; r++) lc[r] -= lt[r] * f;
            }
            d = lc[c];
            if (!(d > 0.0) || !dfm__finite(d)) return (long)c;
            d = sqrt(d);
            lc[c] = d;
            inv = 1.0 / d;
            for (r = c + 1; r < end; r++) lc[r] *= inv;
        }
        if (nr > end) dfm__trsm_rows(nr - end, jb, L + j0 + j0 * ld, L + end + j0 * ld, ld);
    }
    return -1;
}

/* ---------------------------------------------------------------------------------------------
   Section: numeric factorization (left-looking supernodal)
   --------------------------------------------------------------------------------------------- */

/* Adds the lower part of a descendant's update U (m x k, rows rows[0..m), the first k of them
   columns of the target) into the target's block Ls (nr rows): U[i,j] goes to row relmap[rows[i]]
   of column relmap[rows[j]]. The rows are sorted, so the tail whose target rows are consecutive
   is added as a straight vector sum; one addition per entry either way (the same bits). */
static void dfm__scatter_update(size_t m, size_t k, const double *U, const int32_t *rows, const int32_t *relmap,
                                int32_t *rel, double *Ls, size_t nr)
{
    size_t i, j, q;
    for (i = 0; i < m; i++) rel[i] = relmap[rows[i]];
    for (q = m - 1; q > 0 && rel[q - 1] + 1 == rel[q]; q--) {
    }
    for (j = 0; j < k; j++) {
        double *col = Ls + (size_t)rel[j] * nr;
        const double *u = U + j * m;
        size_t e = q > j ? q : j;
        double *c = col + rel[e];
        for (i = j; i < e; i++) col[rel[i]] += u[i];
        u += e;
        i = 0;
#ifdef DFM__V2
        for (; i + 2 <= m - e; i += 2) dfm__st2(c + i, dfm__ld2(c + i) + dfm__ld2(u + i));
#endif
        for (; i < m - e; i++) c[i] += u[i];
    }
}

/* The factorization's workspace: the linked lists of descendants waiting for each supernode
   (link_head / link_next), each factored supernode's first row not yet applied (pos), the target's
   relative row map (relmap, rel), one descendant's update (upd) and the gemm's packing (ws). */
typedef struct dfm__factor_ws {
    int32_t *link_head, *link_next, *relmap, *rel;
    size_t *pos;
    double *upd, *ws;
} dfm__factor_ws;

static void dfm__factor_ws_free(const dfm_allocator *al, dfm__factor_ws *w)
{
    dfm__free(al, w->link_head);
    dfm__free(al, w->link_next);
    dfm__free(al, w->pos);
    dfm__free(al, w->relmap);
    dfm__free(al, w->rel);
    dfm__free(al, w->upd);
    dfm__free(al, w->ws);
}

static dfm_result dfm__factor_ws_alloc(const dfm_chol *chol, dfm__factor_ws *w)
{
    const dfm_allocator *al = &chol->al;
    dfm_result err = DFM_OK;
    size_t s, ns = chol->nsuper, widest = 0;
    memset(w, 0, sizeof *w);
    w->link_head = (int32_t *)dfm__alloc(al, ns, sizeof(int32_t), &err);
    w->link_next = (int32_t *)dfm__alloc(al, ns, sizeof(int32_t), &err);
    w->pos = (size_t *)dfm__alloc(al, ns, sizeof(size_t), &err);
    w->relmap = (int32_t *)dfm__alloc(al, chol->n, sizeof(int32_t), &err);
    w->rel = (int32_t *)dfm__alloc(al, chol->max_rows + 1, sizeof(int32_t), &err);
    w->upd = (double *)dfm__alloc(al, chol->max_update, sizeof(double), &err);
    for (s = 0; s < ns; s++) /* the widest supernode: the gemm's largest inner dimension */
        if ((size_t)(chol->sup_first[s + 1] - chol->sup_first[s]) > widest)
            widest = (size_t)(chol->sup_first[s + 1] - chol->sup_first[s]);
    if (dfm__gemm_ws(widest) > 0) w->ws = (double *)dfm__alloc(al, dfm__gemm_ws(widest), sizeof(double), &err);
    if (err == DFM_OK)
        for (s = 0; s < ns; s++) w->link_head[s] = -1;
    return err;
}

/* a's pattern and kind must be the analysed ones, its values finite */
static dfm_result dfm__factor_check(const dfm_chol *chol, const dfm_csc *a)
{
    dfm_result err = dfm__validate_pattern(a);
    if (err != DFM_OK) return err;
    if (a->kind != DFM_CSC_SYMMETRIC_LOWER || a->n_cols != chol->n || a->col_start[a->n_cols] != chol->nnz_a ||
        dfm__pattern_hash(a) != chol->pattern_hash)
        return DFM_ERR_PATTERN_MISMATCH;
    return dfm__validate_values(a);
}

/* A's columns of supernode s into its block (zeroed first), and relmap for its rows */
static void dfm__assemble_supernode(dfm_chol *chol, const dfm_csc *a, size_t s, int32_t *relmap)
{
    size_t f = (size_t)chol->sup_first[s], l = (size_t)chol->sup_first[s + 1], t, r;
    const int32_t *rs = chol->rows + chol->sup_rowptr[s];
    size_t nr = chol->sup_rowptr[s + 1] - chol->sup_rowptr[s];
    memset(chol->values + chol->sup_valptr[s], 0, nr * (l - f) * sizeof(double));
    for (t = chol->amap_start[f]; t < chol->amap_start[l]; t++) chol->values[chol->amap_dst[t]] += a->values[chol->amap_src[t]];
    for (r = 0; r < nr; r++) relmap[rs[r]] = (int32_t)r;
}

/* Factored supernode d has applied its rows before p: it waits next in the list of the supernode
   that holds its row p (if any). */
static void dfm__link_to_next(const dfm_chol *chol, dfm__factor_ws *w, size_t d, size_t p)
{
    w->pos[d] = p;
    if (p < chol->sup_rowptr[d + 1] - chol->sup_rowptr[d]) {
        int32_t target = chol->col_super[chol->rows[chol->sup_rowptr[d] + p]];
        w->link_next[d] = w->link_head[target];
        w->link_head[target] = (int32_t)d;
    }
}

/* Subtracts from supernode s the update L_d,rows L_d,cols^T of every descendant d with rows in s's
   columns (left-looking), and moves each on to its next target. */
static void dfm__apply_descendants(dfm_chol *chol, size_t s, dfm__factor_ws *w)
{
    size_t f = (size_t)chol->sup_first[s], l = (size_t)chol->sup_first[s + 1], nc = l - f;
    size_t nr = chol->sup_rowptr[s + 1] - chol->sup_rowptr[s];
    double *Ls = chol->values + chol->sup_valptr[s];
    int32_t d, dnext;
    for (d = w->link_head[s]; d != -1; d = dnext) {
        const int32_t *rd = chol->rows + chol->sup_rowptr[d];
        size_t nrd = chol->sup_rowptr[d + 1] - chol->sup_rowptr[d];
        size_t ncd = (size_t)(chol->sup_first[d + 1] - chol->sup_first[d]);
        const double *Ld = chol->values + chol->sup_valptr[d];
        size_t p0 = w->pos[d], p1 = p0, m, k;
        dnext = w->link_next[d];
        while (p1 < nrd && (size_t)rd[p1] < l) p1++;
        m = nrd - p0;
        k = p1 - p0;
        if (m == nr && k == nc && (size_t)rd[p0] == f) {
            /* the descendant's rows are exactly this supernode's: update in place */
            dfm__gemm(m, k, ncd, Ld + p0, nrd, Ld + p0, nrd, Ls, nr, 0, w->ws);
        } else {
            dfm__gemm(m, k, ncd, Ld + p0, nrd, Ld + p0, nrd, w->upd, m, 1, w->ws);
            dfm__scatter_update(m, k, w->upd, rd + p0, w->relmap, w->rel, Ls, nr);
        }
        dfm__link_to_next(chol, w, (size_t)d, p1);
    }
}

/* Counts supernode s's work and reports every 1/64 of the total; nonzero when the user cancels. */
static int dfm__factor_progress(const dfm_chol *chol, size_t s, double *flops_done, double *next_report)
{
    size_t f = (size_t)chol->sup_first[s], l = (size_t)chol->sup_first[s + 1], j;
    size_t nr = chol->sup_rowptr[s + 1] - chol->sup_rowptr[s];
    double done;
    for (j = f; j < l; j++) *flops_done += (double)(nr - (j - f)) * (double)(nr - (j - f));
    if (*flops_done < *next_report) return 0;
    *next_report += chol->flops / 64.0;
    /* the supernodes' rows include the amalgamation's zeros, which chol->flops (from the column
       counts) does not: the share can pass 1 */
    done = *flops_done / (chol->flops > 0 ? chol->flops : 1.0);
    return chol->progress(chol->progress_user, (float)(done < 1.0 ? done : 1.0)) != 0;
}

/* Left-looking supernodal factorization: each supernode in order is assembled from A, updated by
   its descendants, factored as a dense panel, then queued for its first ancestor. */
DFMDEF dfm_result dfm_chol_factor(dfm_chol *chol, const dfm_csc *a)
{
    dfm__factor_ws w;
    dfm_result err;
    size_t s;
    double flops_done = 0.0, next_report;
    if (!chol) return DFM_ERR_INVALID_ARGUMENT;
    chol->factored = 0;
    chol->failed_column = -1;
    err = dfm__factor_check(chol, a);
    if (err != DFM_OK) return err;
    err = dfm__factor_ws_alloc(chol, &w);
    next_report = chol->flops / 64.0;
    for (s = 0; err == DFM_OK && s < chol->nsuper; s++) {
        size_t f = (size_t)chol->sup_first[s], nc = (size_t)chol->sup_first[s + 1] - f;
        size_t nr = chol->sup_rowptr[s + 1] - chol->sup_rowptr[s];
        long fail;
        dfm__assemble_supernode(chol, a, s, w.relmap);
        dfm__apply_descendants(chol, s, &w);
        fail = dfm__panel_chol(nr, nc, chol->values + chol->sup_valptr[s], nr, w.ws);
        if (fail >= 0) {
            chol->failed_column = (long long)chol->perm[f + (size_t)fail];
            err = DFM_ERR_NOT_POSITIVE_DEFINITE;
        } else {
            dfm__link_to_next(chol, &w, s, nc);
            if (chol->progress && dfm__factor_progress(chol, s, &flops_done, &next_report)) err = DFM_CANCELLED;
        }
    }
    if (err == DFM_OK) chol->factored = 1;
    dfm__factor_ws_free(&chol->al, &w);
    return err;
}

/* ---------------------------------------------------------------------------------------------
   Section: solves
   --------------------------------------------------------------------------------------------- */

/* L Y = X and L^T Z = Y on q <= 4 interleaved right-hand sides: w[k*q + t] is row k (new
   numbering) of right-hand side t. Every entry of L is loaded once per direction and used for
   all q right-hand sides; the solve is bound by reading L from memory. */
static void dfm__solve_generic(const dfm_chol *c, double *w, size_t q)
{
    size_t s, ns = c->nsuper, t, cc, r;
    for (s = 0; s < ns; s++) {
        size_t f = (size_t)c->sup_first[s], nc = (size_t)c->sup_first[s + 1] - f;
        size_t nr = c->sup_rowptr[s + 1] - c->sup_rowptr[s];
        const int32_t *rs = c->rows + c->sup_rowptr[s];
        const double *Ls = c->values + c->sup_valptr[s];
        for (cc = 0; cc < nc; cc++) {
            const double *lc = Ls + cc * nr;
            double *xc = w + (f + cc) * q, inv = 1.0 / lc[cc];
            for (t = 0; t < q; t++) xc[t] *= inv;
            for (r = cc + 1; r < nr; r++) {
                double *xr = w + (size_t)rs[r] * q, v = lc[r];
                for (t = 0; t < q; t++) xr[t] -= v * xc[t];
            }
        }
    }
    for (s = ns; s-- > 0;) {
        size_t f = (size_t)c->sup_first[s], nc = (size_t)c->sup_first[s + 1] - f;
        size_t nr = c->sup_rowptr[s + 1] - c->sup_rowptr[s];
        const int32_t *rs = c->rows + c->sup_rowptr[s];
        const double *Ls = c->values + c->sup_valptr[s];
        for (cc = nc; cc-- > 0;) {
            const double *lc = Ls + cc * nr;
            double *xc = w + (f + cc) * q, inv = 1.0 / lc[cc];
            for (r = cc + 1; r < nr; r++) {
                const double *xr = w + (size_t)rs[r] * q;
                double v = lc[r];
                for (t = 0; t < q; t++) xc[t] -= v * xr[t];
            }
            for (t = 0; t < q; t++) xc[t] *= inv;
        }
    }
}

#ifdef DFM__V2
/* dfm__solve3, forward substitution L y = b for supernode s */
static void dfm__solve3_forward(const dfm_chol *c, size_t s, double *w, double *tmp)
{
    size_t cc, r, k;
    size_t f = (size_t)c->sup_first[s], nc = (size_t)c->sup_first[s + 1] - f;
    size_t nr = c->sup_rowptr[s + 1] - c->sup_rowptr[s];
    const int32_t *rs = c->rows + c->sup_rowptr[s];
    const double *Ls = c->values + c->sup_valptr[s];
    double *y = tmp;
    memcpy(y, w + 3 * f, 3 * nc * sizeof(double));
    memset(y + 3 * nc, 0, 3 * (nr - nc) * sizeof(double));
    for (cc = 0; cc + 4 <= nc; cc += 4) {
        const double *l[4];
        dfm__v2 xy[4];
        double z[4];
        size_t i2;
        for (k = 0; k < 4; k++) l[k] = Ls + (cc + k) * nr;
        /* the 4 x 4 triangle */
        for (k = 0; k < 4; k++) {
            dfm__v2 t = dfm__ld2(y + 3 * (cc + k));
            double tz = y[3 * (cc + k) + 2], d = l[k][cc + k];
            dfm__v2 dv = {d, d};
            for (i2 = 0; i2 < k; i2++) {
                double e = l[i2][cc + k];
                dfm__v2 ev = {e, e};
                t -= ev * xy[i2];
                tz -= e * z[i2];
            }
            xy[k] = t / dv;
            z[k] = tz / d;
            dfm__st2(y + 3 * (cc + k), xy[k]);
            y[3 * (cc + k) + 2] = z[k];
        }
        for (r = cc + 4; r < nr; r++) {
            double v0 = l[0][r], v1 = l[1][r], v2 = l[2][r], v3 = l[3][r];
            double *yr = y + 3 * r;
            dfm__v2 w0 = {v0, v0}, w1 = {v1, v1}, w2 = {v2, v2}, w3 = {v3, v3};
            dfm__st2(yr, dfm__ld2(yr) - ((w0 * xy[0] + w1 * xy[1]) + (w2 * xy[2] + w3 * xy[3])));
            yr[2] -= (v0 * z[0] + v1 * z[1]) + (v2 * z[2] + v3 * z[3]);
        }
    }
    for (; cc < nc; cc++) {
        const double *l0 = Ls + cc * nr;
        double d0 = l0[cc], z0;
        dfm__v2 dv = {d0, d0}, xy0 = dfm__ld2(y + 3 * cc) / dv;
        z0 = y[3 * cc + 2] / d0;
        dfm__st2(y + 3 * cc, xy0);
        y[3 * cc + 2] = z0;
        for (r = cc + 1; r < nr; r++) {
            double v0 = l0[r];
            double *yr = y + 3 * r;
            dfm__v2 w0 = {v0, v0};
            dfm__st2(yr, dfm__ld2(yr) - w0 * xy0);
            yr[2] -= v0 * z0;
        }
    }
    memcpy(w + 3 * f, y, 3 * nc * sizeof(double));
    for (r = nc; r < nr; r++) {
        double *xr = w + 3 * (size_t)rs[r];
        const double *yr = y + 3 * r;
        xr[0] += yr[0];
        xr[1] += yr[1];
        xr[2] += yr[2];
    }
}

/* dfm__solve3, backward substitution L^T x = y for supernode s */
static void dfm__solve3_backward(const dfm_chol *c, size_t s, double *w, double *tmp)
{
    size_t cc, r, k;
    size_t f = (size_t)c->sup_first[s], nc = (size_t)c->sup_first[s + 1] - f;
    size_t nr = c->sup_rowptr[s + 1] - c->sup_rowptr[s];
    const int32_t *rs = c->rows + c->sup_rowptr[s];
    const double *Ls = c->values + c->sup_valptr[s];
    double *y = tmp;
    size_t nb = nc & ~(size_t)3; /* columns [0, nb) go in blocks of 4, the rest one by one */
    memcpy(y, w + 3 * f, 3 * nc * sizeof(double));
    for (r = nc; r < nr; r++) {
        const double *xr = w + 3 * (size_t)rs[r];
        double *yr = y + 3 * r;
        yr[0] = xr[0];
        yr[1] = xr[1];
        yr[2] = xr[2];
    }
    for (cc = nc; cc-- > nb;) {
        const double *l0 = Ls + cc * nr;
        dfm__v2 xy0 = dfm__ld2(y + 3 * cc);
        double z0 = y[3 * cc + 2], d0 = l0[cc];
        dfm__v2 dv = {d0, d0};
        for (r = cc + 1; r < nr; r++) {
            double v0 = l0[r];
            const double *yr = y + 3 * r;
            dfm__v2 w0 = {v0, v0};
            xy0 -= w0 * dfm__ld2(yr);
            z0 -= v0 * yr[2];
        }
        dfm__st2(y + 3 * cc, xy0 / dv);
        y[3 * cc + 2] = z0 / d0;
    }
    for (cc = nb; cc >= 4; cc -= 4) {
        size_t c0 = cc - 4, i2;
        const double *l[4];
        dfm__v2 xy[4];
        double z[4];
        for (k = 0; k < 4; k++) {
            l[k] = Ls + (c0 + k) * nr;
            xy[k] = dfm__ld2(y + 3 * (c0 + k));
            z[k] = y[3 * (c0 + k) + 2];
        }
        for (r = cc; r < nr; r++) {
            double v0 = l[0][r], v1 = l[1][r], v2 = l[2][r], v3 = l[3][r];
            const double *yr = y + 3 * r;
            dfm__v2 pq = dfm__ld2(yr), w0 = {v0, v0}, w1 = {v1, v1}, w2 = {v2, v2}, w3 = {v3, v3};
            double u = yr[2];
            xy[0] -= w0 * pq;
            xy[1] -= w1 * pq;
            xy[2] -= w2 * pq;
            xy[3] -= w3 * pq;
            z[0] -= v0 * u;
            z[1] -= v1 * u;
            z[2] -= v2 * u;
            z[3] -= v3 * u;
        }
        /* the 4 x 4 block of L^T, bottom up */
        for (k = 4; k-- > 0;) {
            double d = l[k][c0 + k];
            dfm__v2 dv = {d, d};
            for (i2 = k + 1; i2 < 4; i2++) {
                double e = l[k][c0 + i2];
                dfm__v2 ev = {e, e};
                xy[k] -= ev * xy[i2];
                z[k] -= e * z[i2];
            }
            xy[k] /= dv;
            z[k] /= d;
            dfm__st2(y + 3 * (c0 + k), xy[k]);
            y[3 * (c0 + k) + 2] = z[k];
        }
    }
    memcpy(w + 3 * f, y, 3 * nc * sizeof(double));
}

/* The same for exactly 3 right-hand sides (x, y, z), the common case, with the supernode's rows
   gathered into the dense tmp (3 x nrows, interleaved) so that the indirect row accesses happen
   once a row per supernode, and columns taken four at a time (a quarter of the traffic on tmp).
   x and y of a row travel in one two-lane vector, z beside it. */
static void dfm__solve3(const dfm_chol *c, double *w, double *tmp)
{
    size_t s, ns = c->nsuper;
    for (s = 0; s < ns; s++) dfm__solve3_forward(c, s, w, tmp);
    for (s = ns; s-- > 0;)
        dfm__solve3_backward(c, s, w, tmp);
}
#endif

#if defined(DFM__V2) && defined(DFM__AVX)
/* dfm__solve3_avx, forward substitution L y = b for supernode s */
__attribute__((target("avx"))) static void dfm__solve3_avx_forward(const dfm_chol *c, size_t s, double *w, double *tmp)
{
    size_t cc, r, k, i2;
    dfm__v4 zero = {0.0, 0.0, 0.0, 0.0};
    size_t f = (size_t)c->sup_first[s], nc = (size_t)c->sup_first[s + 1] - f;
    size_t nr = c->sup_rowptr[s + 1] - c->sup_rowptr[s];
    const int32_t *rs = c->rows + c->sup_rowptr[s];
    const double *Ls = c->values + c->sup_valptr[s];
    dfm__v4 *y = (dfm__v4 *)(void *)tmp;
    for (r = 0; r < nc; r++) {
        const double *x = w + 3 * (f + r);
        dfm__v4 v = {x[0], x[1], x[2], 0.0};
        y[r] = v;
    }
    for (r = nc; r < nr; r++) y[r] = zero;
    for (cc = 0; cc + 4 <= nc; cc += 4) {
        const double *l[4];
        dfm__v4 x[4];
        for (k = 0; k < 4; k++) l[k] = Ls + (cc + k) * nr;
        for (k = 0; k < 4; k++) {
            dfm__v4 t = y[cc + k];
            double d = l[k][cc + k];
            dfm__v4 dv = {d, d, d, d};
            for (i2 = 0; i2 < k; i2++) {
                double e = l[i2][cc + k];
                dfm__v4 ev = {e, e, e, e};
                t -= ev * x[i2];
            }
            x[k] = t / dv;
            y[cc + k] = x[k];
        }
        for (r = cc + 4; r < nr; r++) {
            double v0 = l[0][r], v1 = l[1][r], v2 = l[2][r], v3 = l[3][r];
            dfm__v4 w0 = {v0, v0, v0, v0}, w1 = {v1, v1, v1, v1}, w2 = {v2, v2, v2, v2}, w3 = {v3, v3, v3, v3};
            y[r] -= (w0 * x[0] + w1 * x[1]) + (w2 * x[2] + w3 * x[3]);
        }
    }
    for (; cc < nc; cc++) {
        const double *l0 = Ls + cc * nr;
        double d0 = l0[cc];
        dfm__v4 dv = {d0, d0, d0, d0}, x0 = y[cc] / dv;
        y[cc] = x0;
        for (r = cc + 1; r < nr; r++) {
            double v0 = l0[r];
            dfm__v4 w0 = {v0, v0, v0, v0};
            y[r] -= w0 * x0;
        }
    }
    for (r = 0; r < nc; r++) {
        double *x = w + 3 * (f + r);
        x[0] = y[r][0];
        x[1] = y[r][1];
        x[2] = y[r][2];
    }
    for (r = nc; r < nr; r++) {
        double *x = w + 3 * (size_t)rs[r];
        x[0] += y[r][0];
        x[1] += y[r][1];
        x[2] += y[r][2];
    }
}

/* dfm__solve3_avx, backward substitution L^T x = y for supernode s */
__attribute__((target("avx"))) static void dfm__solve3_avx_backward(const dfm_chol *c, size_t s, double *w, double *tmp)
{
    size_t cc, r, k, i2;
    size_t f = (size_t)c->sup_first[s], nc = (size_t)c->sup_first[s + 1] - f;
    size_t nr = c->sup_rowptr[s + 1] - c->sup_rowptr[s];
    const int32_t *rs = c->rows + c->sup_rowptr[s];
    const double *Ls = c->values + c->sup_valptr[s];
    dfm__v4 *y = (dfm__v4 *)(void *)tmp;
    size_t nb = nc & ~(size_t)3;
    for (r = 0; r < nr; r++) {
        const double *x = w + 3 * (r < nc ? f + r : (size_t)rs[r]);
        dfm__v4 v = {x[0], x[1], x[2], 0.0};
        y[r] = v;
    }
    for (cc = nc; cc-- > nb;) {
        const double *l0 = Ls + cc * nr;
        dfm__v4 x0 = y[cc];
        double d0 = l0[cc];
        dfm__v4 dv = {d0, d0, d0, d0};
        for (r = cc + 1; r < nr; r++) {
            double v0 = l0[r];
            dfm__v4 w0 = {v0, v0, v0, v0};
            x0 -= w0 * y[r];
        }
        y[cc] = x0 / dv;
    }
    for (cc = nb; cc >= 4; cc -= 4) {
        size_t c0 = cc - 4;
        const double *l[4];
        dfm__v4 x[4];
        for (k = 0; k < 4; k++) {
            l[k] = Ls + (c0 + k) * nr;
            x[k] = y[c0 + k];
        }
        for (r = cc; r < nr; r++) {
            double v0 = l[0][r], v1 = l[1][r], v2 = l[2][r], v3 = l[3][r];
            dfm__v4 pq = y[r], w0 = {v0, v0, v0, v0}, w1 = {v1, v1, v1, v1}, w2 = {v2, v2, v2, v2};
            dfm__v4 w3 = {v3, v3, v3, v3};
            x[0] -= w0 * pq;
            x[1] -= w1 * pq;
            x[2] -= w2 * pq;
            x[3] -= w3 * pq;
        }
        for (k = 4; k-- > 0;) {
            double d = l[k][c0 + k];
            dfm__v4 dv = {d, d, d, d};
            for (i2 = k + 1; i2 < 4; i2++) {
                double e = l[k][c0 + i2];
                dfm__v4 ev = {e, e, e, e};
                x[k] -= ev * x[i2];
            }
            x[k] /= dv;
            y[c0 + k] = x[k];
        }
    }
    for (r = 0; r < nc; r++) {
        double *x = w + 3 * (f + r);
        x[0] = y[r][0];
        x[1] = y[r][1];
        x[2] = y[r][2];
    }
}

/* dfm__solve3 with the row's x, y, z in one four-lane vector (tmp rows padded to 4 doubles),
   compiled for AVX and chosen at run time; the same operations in the same order per lane, so
   the same bits as dfm__solve3. */
__attribute__((target("avx"))) static void dfm__solve3_avx(const dfm_chol *c, double *w, double *tmp)
{
    size_t s, ns = c->nsuper;
    /* the vectors need 32-byte alignment: the caller left 4 spare doubles */
    tmp = (double *)(void *)(((uintptr_t)tmp + 31u) & ~(uintptr_t)31u);
    for (s = 0; s < ns; s++) dfm__solve3_avx_forward(c, s, w, tmp);
    for (s = ns; s-- > 0;)
        dfm__solve3_avx_backward(c, s, w, tmp);
}
#endif

static void dfm__solve_interleaved(const dfm_chol *c, double *w, size_t q, double *tmp)
{
#ifdef DFM__V2
    if (q == 3) {
#ifdef DFM__AVX
        if (__builtin_cpu_supports("avx")) {
            dfm__solve3_avx(c, w, tmp);
            return;
        }
#endif
        dfm__solve3(c, w, tmp);
        return;
    }
#endif
    (void)tmp;
    dfm__solve_generic(c, w, q);
}

DFMDEF dfm_result dfm_chol_solve(const dfm_chol *c, double *x, size_t nrhs)
{
    dfm_result err = DFM_OK;
    size_t n, q0, k, t;
    double *w;
    if (!c || (!x && nrhs > 0)) return DFM_ERR_INVALID_ARGUMENT;
    if (!c->factored) return DFM_ERR_INVALID_ARGUMENT;
    if (nrhs == 0) return DFM_OK;
    n = c->n;
    if (nrhs > ((size_t)-1 >> 4) / n) return DFM_ERR_TOO_LARGE;
    if (!dfm__all_finite(x, n * nrhs)) return DFM_ERR_BAD_VALUE; /* x is left as it was */
    /* room for the supernode block: 4 doubles a row (the AVX solve pads rows to 4) */
    w = (double *)dfm__alloc(&c->al, n * (nrhs < 4 ? nrhs : 4) + 4 * c->max_rows + 4, sizeof(double), &err);
    if (!w) return err;
    for (q0 = 0; q0 < nrhs; q0 += 4) {
        size_t q = nrhs - q0 < 4 ? nrhs - q0 : 4;
        double *xq = x + q0 * n;
        for (k = 0; k < n; k++)
            for (t = 0; t < q; t++) w[k * q + t] = xq[(size_t)c->perm[k] + t * n];
        dfm__solve_interleaved(c, w, q, w + n * (nrhs < 4 ? nrhs : 4));
        for (k = 0; k < n; k++)
            for (t = 0; t < q; t++) xq[(size_t)c->perm[k] + t * n] = w[k * q + t];
    }
    dfm__free(&c->al, w);
    return dfm__all_finite(x, n * nrhs) ? DFM_OK : DFM_ERR_NOT_FINITE; /* overflow: a tiny pivot */
}

DFMDEF dfm_result dfm_chol_solve_refined(const dfm_chol *c, const dfm_csc *a, const double *b, double *x,
                                         size_t nrhs, int max_steps)
{
    dfm_result err = DFM_OK;
    size_t n, i;
    double *r = NULL, prev = HUGE_VAL;
    int step;
    if (!c || !a || ((!b || !x) && nrhs > 0)) return DFM_ERR_INVALID_ARGUMENT;
    if (a->n_cols != c->n || a->kind != DFM_CSC_SYMMETRIC_LOWER) return DFM_ERR_PATTERN_MISMATCH;
    n = c->n;
    if (nrhs == 0) return DFM_OK;
    if (nrhs > ((size_t)-1 >> 4) / n) return DFM_ERR_TOO_LARGE;
    memcpy(x, b, n * nrhs * sizeof(double));
    err = dfm_chol_solve(c, x, nrhs);
    if (err != DFM_OK || max_steps <= 0) return err;
    r = (double *)dfm__alloc(&c->al, n * nrhs, sizeof(double), &err);
    if (!r) return err;
    for (step = 0; step < max_steps; step++) {
        double norm = 0.0;
        err = dfm_csc_multiply(a, x, r, nrhs);
        if (err != DFM_OK) break;
        for (i = 0; i < n * nrhs; i++) {
            r[i] = b[i] - r[i];
            if (fabs(r[i]) > norm) norm = fabs(r[i]);
        }
        if (!(norm < prev) || norm == 0.0) break;
        prev = norm;
        err = dfm_chol_solve(c, r, nrhs);
        if (err != DFM_OK) break;
        for (i = 0; i < n * nrhs; i++) x[i] += r[i];
    }
    dfm__free(&c->al, r);
    /* b was finite (the first solve checked it): a non-finite residual or step is an overflow */
    if (err == DFM_ERR_BAD_VALUE || (err == DFM_OK && !dfm__all_finite(x, n * nrhs))) err = DFM_ERR_NOT_FINITE;
    return err;
}

DFMDEF const int32_t *dfm_chol_permutation(const dfm_chol *c) { return c ? c->perm : NULL; }

DFMDEF const size_t *dfm_chol_column_counts(const dfm_chol *c) { return c ? c->colcount : NULL; }

DFMDEF void dfm_chol_get_info(const dfm_chol *c, dfm_chol_info *info)
{
    if (!info) return;
    memset(info, 0, sizeof *info);
    info->failed_column = -1;
    if (!c) return;
    info->n = c->n;
    info->nnz_l = c->nnz_l;
    info->stored_entries = c->sup_valptr[c->nsuper];
    info->supernodes = c->nsuper;
    info->flops = c->flops;
    info->factored = c->factored;
    info->failed_column = c->failed_column;
}

/* ---------------------------------------------------------------------------------------------
   Section: hard constraints by elimination
   --------------------------------------------------------------------------------------------- */

struct dfm_constrained {
    dfm_allocator al;
    size_t n, nfree;
    int32_t *free_index;   /* n: index among the free unknowns, or -1 when fixed */
    int32_t *free_rows;    /* nfree: input index of each free unknown */
    dfm_csc aff;           /* free-free block (pattern; values refreshed by factor) */
    size_t *aff_src;       /* nnz(aff): index into a->values */
    size_t ncoup;
    int32_t *coup_free, *coup_fixed; /* coupling entries: free row, fixed column */
    size_t *coup_src;
    double *coup_val;
    size_t nnz_a;
    uint64_t pattern_hash;
    dfm_chol *chol;
};

DFMDEF void dfm_constrained_free(dfm_constrained *c)
{
    dfm_allocator al;
    if (!c) return;
    al = c->al;
    dfm__free(&al, c->free_index);
    dfm__free(&al, c->free_rows);
    dfm_csc_free(&c->aff);
    dfm__free(&al, c->aff_src);
    dfm__free(&al, c->coup_free);
    dfm__free(&al, c->coup_fixed);
    dfm__free(&al, c->coup_src);
    dfm__free(&al, c->coup_val);
    dfm_chol_free(c->chol);
    dfm__free(&al, c);
}

DFMDEF const dfm_chol *dfm_constrained_chol(const dfm_constrained *c) { return c ? c->chol : NULL; }

DFMDEF dfm_result dfm_constrained_analyze(const dfm_csc *a, const unsigned char *fixed,
                                          const dfm_chol_options *options, dfm_constrained **out)
{
    dfm_chol_options opt = options ? *options : dfm_chol_default_options();
    dfm_allocator al = dfm__resolve_allocator(opt.allocator);
    dfm_result err;
    dfm_constrained *c;
    size_t n, j, p, nnz_ff = 0, ncoup = 0, w = 0, wc = 0;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    *out = NULL;
    err = dfm__validate_pattern(a);
    if (err != DFM_OK) return err;
    if (!fixed || a->kind != DFM_CSC_SYMMETRIC_LOWER || a->n_cols == 0) return DFM_ERR_INVALID_ARGUMENT;
    if (opt.block_size > 1 || opt.ordering == DFM_ORDER_GIVEN) {
        /* block structure and given permutations refer to the full system: order the free block
           by AMD instead */
        opt.block_size = 1;
        opt.ordering = DFM_ORDER_AMD;
    }
    n = a->n_cols;
    c = (dfm_constrained *)dfm__alloc(&al, 1, sizeof *c, &err);
    if (!c) return err;
    memset(c, 0, sizeof *c);
    c->al = al;
    c->n = n;
    c->nnz_a = a->col_start[n];
    c->pattern_hash = dfm__pattern_hash(a);
    c->free_index = (int32_t *)dfm__alloc(&al, n, sizeof(int32_t), &err);
    c->free_rows = (int32_t *)dfm__alloc(&al, n, sizeof(int32_t), &err);
    if (err != DFM_OK) goto fail;
    for (j = 0; j < n; j++) {
        c->free_index[j] = fixed[j] ? -1 : (int32_t)c->nfree;
        if (!fixed[j]) c->free_rows[c->nfree++] = (int32_t)j;
    }
    if (c->nfree == 0) {
        err = DFM_ERR_INVALID_ARGUMENT;
        goto fail;
    }
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            int32_t i = a->row_index[p];
            int fi = c->free_index[i] >= 0, fj = c->free_index[j] >= 0;
            if (fi && fj) nnz_ff++;
            else if (fi != fj) ncoup++;
        }
    err = dfm_csc_alloc(c->nfree, c->nfree, nnz_ff, DFM_CSC_SYMMETRIC_LOWER, &al, &c->aff);
    if (err != DFM_OK) goto fail;
    c->aff_src = (size_t *)dfm__alloc(&al, nnz_ff, sizeof(size_t), &err);
    c->coup_free = (int32_t *)dfm__alloc(&al, ncoup, sizeof(int32_t), &err);
    c->coup_fixed = (int32_t *)dfm__alloc(&al, ncoup, sizeof(int32_t), &err);
    c->coup_src = (size_t *)dfm__alloc(&al, ncoup, sizeof(size_t), &err);
    c->coup_val = (double *)dfm__alloc(&al, ncoup, sizeof(double), &err);
    if (err != DFM_OK) goto fail;
    c->ncoup = ncoup;
    for (j = 0; j < n; j++) {
        int32_t fj = c->free_index[j];
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            int32_t i = a->row_index[p], fi = c->free_index[i];
            if (fi >= 0 && fj >= 0) {
                c->aff.row_index[w] = fi;
                c->aff.values[w] = 0.0;
                c->aff_src[w++] = p;
            } else if ((fi >= 0) != (fj >= 0)) {
                c->coup_free[wc] = fi >= 0 ? fi : fj;
                c->coup_fixed[wc] = fi >= 0 ? (int32_t)j : i;
                c->coup_src[wc++] = p;
            }
        }
        if (fj >= 0) c->aff.col_start[fj + 1] = w;
    }
    if (opt.coords) {
        /* the free block is renumbered: its coordinates are the free rows' */
        double *fc = (double *)dfm__alloc(&al, c->nfree, 3 * sizeof(double), &err);
        const double *all = opt.coords;
        if (!fc) goto fail;
        for (j = 0; j < c->nfree; j++) memcpy(fc + 3 * j, all + 3 * (size_t)c->free_rows[j], 3 * sizeof(double));
        opt.coords = fc;
        err = dfm_chol_analyze(&c->aff, &opt, &c->chol);
        dfm__free(&al, fc);
    } else {
        err = dfm_chol_analyze(&c->aff, &opt, &c->chol);
    }
    if (err != DFM_OK) goto fail;
    *out = c;
    return DFM_OK;
fail:
    dfm_constrained_free(c);
    return err;
}

DFMDEF dfm_result dfm_constrained_factor(dfm_constrained *c, const dfm_csc *a)
{
    size_t p;
    dfm_result err;
    if (!c) return DFM_ERR_INVALID_ARGUMENT;
    err = dfm__validate_pattern(a);
    if (err != DFM_OK) return err;
    if (a->n_cols != c->n || a->col_start[a->n_cols] != c->nnz_a || dfm__pattern_hash(a) != c->pattern_hash)
        return DFM_ERR_PATTERN_MISMATCH;
    err = dfm__validate_values(a);
    if (err != DFM_OK) return err;
    for (p = 0; p < c->aff.col_start[c->nfree]; p++) c->aff.values[p] = a->values[c->aff_src[p]];
    for (p = 0; p < c->ncoup; p++) c->coup_val[p] = a->values[c->coup_src[p]];
    err = dfm_chol_factor(c->chol, &c->aff);
    if (err == DFM_ERR_NOT_POSITIVE_DEFINITE)
        c->chol->failed_column = (long long)c->free_rows[c->chol->failed_column];
    return err;
}

DFMDEF dfm_result dfm_constrained_solve(const dfm_constrained *c, const double *b, const double *fixed_values,
                                        double *x, size_t nrhs)
{
    dfm_result err = DFM_OK;
    size_t n, nf, q, k;
    double *w;
    if (!c || ((!b || !fixed_values || !x) && nrhs > 0)) return DFM_ERR_INVALID_ARGUMENT;
    if (nrhs == 0) return DFM_OK;
    n = c->n;
    nf = c->nfree;
    if (nrhs > ((size_t)-1 >> 4) / n) return DFM_ERR_TOO_LARGE;
    for (q = 0; q < nrhs; q++)
        for (k = 0; k < n; k++)
            if (!dfm__finite(c->free_index[k] < 0 ? fixed_values[q * n + k] : b[q * n + k])) return DFM_ERR_BAD_VALUE;
    w = (double *)dfm__alloc(&c->al, nf * nrhs, sizeof(double), &err);
    if (!w) return err;
    for (q = 0; q < nrhs; q++) {
        const double *bq = b + q * n, *fq = fixed_values + q * n;
        double *wq = w + q * nf;
        for (k = 0; k < nf; k++) wq[k] = bq[c->free_rows[k]];
        for (k = 0; k < c->ncoup; k++) wq[c->coup_free[k]] -= c->coup_val[k] * fq[c->coup_fixed[k]];
    }
    err = dfm_chol_solve(c->chol, w, nrhs);
    if (err == DFM_ERR_BAD_VALUE) err = DFM_ERR_NOT_FINITE; /* the moved fixed values overflowed */
    if (err == DFM_OK)
        for (q = 0; q < nrhs; q++) {
            double *xq = x + q * n;
            const double *fq = fixed_values + q * n;
            for (k = 0; k < n; k++)
                if (c->free_index[k] < 0) xq[k] = fq[k];
            for (k = 0; k < nf; k++) xq[c->free_rows[k]] = w[q * nf + k];
        }
    dfm__free(&c->al, w);
    return err;
}

/* ---------------------------------------------------------------------------------------------
   Section: deformation - mesh topology, weights and checks
   --------------------------------------------------------------------------------------------- */

/* The vertex graph of a triangle mesh: sorted neighbour lists with a weight per directed edge. */
typedef struct dfm__graph {
    size_t nv;
    size_t *start; /* nv + 1 */
    int32_t *adj;  /* start[nv]: neighbours, sorted */
    double *w;     /* start[nv]: edge weights (symmetric) */
} dfm__graph;

static void dfm__graph_free(dfm__graph *g, const dfm_allocator *al)
{
    dfm__free(al, g->start);
    dfm__free(al, g->adj);
    dfm__free(al, g->w);
    memset(g, 0, sizeof *g);
}

/* position of neighbour j in i's list, or (size_t)-1 */
static size_t dfm__graph_find(const dfm__graph *g, size_t i, int32_t j)
{
    size_t lo = g->start[i], hi = g->start[i + 1];
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (g->adj[mid] < j) lo = mid + 1;
        else hi = mid;
    }
    return lo < g->start[i + 1] && g->adj[lo] == j ? lo : (size_t)-1;
}

static void dfm__sort_i32(int32_t *a, size_t n) { qsort(a, n, sizeof(int32_t), dfm__cmp_i32); }

/* Neighbour lists from the triangles (an index pair repeated in a triangle gives no edge). */
static dfm_result dfm__graph_build(const uint32_t *idx, size_t nt, size_t nv, const dfm_allocator *al,
                                   dfm__graph *g)
{
    dfm_result err = DFM_OK;
    size_t t, k, v, total = 0, *fill = NULL;
    memset(g, 0, sizeof *g);
    g->nv = nv;
    g->start = (size_t *)dfm__alloc(al, nv + 1, sizeof(size_t), &err);
    fill = (size_t *)dfm__alloc(al, nv + 1, sizeof(size_t), &err);
    if (err != DFM_OK) goto done;
    memset(g->start, 0, (nv + 1) * sizeof(size_t));
    for (t = 0; t < 3 * nt; t++) g->start[idx[t] + 1] += 2;
    for (v = 0; v < nv; v++) g->start[v + 1] += g->start[v];
    g->adj = (int32_t *)dfm__alloc(al, g->start[nv] + 1, sizeof(int32_t), &err);
    if (err != DFM_OK) goto done;
    memcpy(fill, g->start, (nv + 1) * sizeof(size_t));
    for (t = 0; t < nt; t++)
        for (k = 0; k < 3; k++) {
            uint32_t a = idx[3 * t + k], b = idx[3 * t + (k + 1) % 3], c = idx[3 * t + (k + 2) % 3];
            if (b != a) g->adj[fill[a]++] = (int32_t)b;
            if (c != a) g->adj[fill[a]++] = (int32_t)c;
        }
    for (v = 0; v < nv; v++) { /* sort, drop duplicates, compact */
        size_t s = g->start[v], e = fill[v], p;
        dfm__sort_i32(g->adj + s, e - s);
        g->start[v] = total;
        for (p = s; p < e; p++)
            if (p == s || g->adj[p] != g->adj[p - 1]) g->adj[total++] = g->adj[p];
    }
    g->start[nv] = total;
    g->w = (double *)dfm__alloc(al, total + 1, sizeof(double), &err);
done:
    dfm__free(al, fill);
    if (err != DFM_OK) dfm__graph_free(g, al);
    return err;
}

/* An edge in more than two triangles is non-manifold; counts kept in g->w (then reset). */
static dfm_result dfm__check_manifold(const uint32_t *idx, size_t nt, dfm__graph *g)
{
    size_t t, k;
    for (k = 0; k < g->start[g->nv]; k++) g->w[k] = 0.0;
    for (t = 0; t < nt; t++)
        for (k = 0; k < 3; k++) {
            uint32_t a = idx[3 * t + k], b = idx[3 * t + (k + 1) % 3];
            size_t p;
            if (a == b) continue;
            p = dfm__graph_find(g, a < b ? a : b, (int32_t)(a < b ? b : a));
            if ((g->w[p] += 1.0) > 2.0) return DFM_ERR_NON_MANIFOLD;
        }
    return DFM_OK;
}


typedef struct dfm__vkey {
    double p[3];
    int32_t v;
} dfm__vkey;

static int dfm__cmp_vkey(const void *x, const void *y)
{
    const dfm__vkey *a = (const dfm__vkey *)x, *b = (const dfm__vkey *)y;
    int k;
    for (k = 0; k < 3; k++)
        if (a->p[k] != b->p[k]) return a->p[k] < b->p[k] ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

/* Two used vertices at exactly the same position: an unwelded mesh (a triangle soup). */
static dfm_result dfm__check_welded(const double *pos, const dfm__graph *g, const dfm_allocator *al)
{
    dfm_result err = DFM_OK;
    size_t v, n = 0;
    dfm__vkey *keys = (dfm__vkey *)dfm__alloc(al, g->nv, sizeof(dfm__vkey), &err);
    if (!keys) return err;
    for (v = 0; v < g->nv; v++)
        if (g->start[v + 1] > g->start[v]) {
            memcpy(keys[n].p, pos + 3 * v, 3 * sizeof(double));
            keys[n++].v = (int32_t)v;
        }
    qsort(keys, n, sizeof *keys, dfm__cmp_vkey);
    for (v = 1; v < n && err == DFM_OK; v++)
        if (!memcmp(keys[v].p, keys[v - 1].p, 3 * sizeof(double))) err = DFM_ERR_UNWELDED;
    dfm__free(al, keys);
    return err;
}

/* A triangle is degenerate when an index repeats or its area is below 1e-12 of |e1| |e2|. */
static int dfm__degenerate(const double *pos, const uint32_t *f)
{
    double u[3], v[3], c[3];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) return 1;
    dfm__sub3(pos + 3 * (size_t)f[1], pos + 3 * (size_t)f[0], u);
    dfm__sub3(pos + 3 * (size_t)f[2], pos + 3 * (size_t)f[0], v);
    dfm__cross3(u, v, c);
    return !(sqrt(dfm__dot3(c, c)) > 1e-12 * sqrt(dfm__dot3(u, u) * dfm__dot3(v, v)));
}

#define DFM__COTAN_FLOOR 1e-3

/* Edge weights: 1 (uniform), or (cot a + cot b) / 2 clamped below at DFM__COTAN_FLOOR. */
static void dfm__edge_weights(const double *pos, const uint32_t *idx, size_t nt, int kind, dfm__graph *g)
{
    size_t t, k, p;
    for (p = 0; p < g->start[g->nv]; p++) g->w[p] = kind == DFM_WEIGHTS_COTAN ? 0.0 : 1.0;
    if (kind != DFM_WEIGHTS_COTAN) return;
    for (t = 0; t < nt; t++) {
        const uint32_t *f = idx + 3 * t;
        if (dfm__degenerate(pos, f)) continue; /* far from the ROI (checked near it) */
        for (k = 0; k < 3; k++) {
            uint32_t o = f[k], a = f[(k + 1) % 3], b = f[(k + 2) % 3];
            double c = 0.5 * dfm__cot_d(pos + 3 * (size_t)o, pos + 3 * (size_t)a, pos + 3 * (size_t)b);
            g->w[dfm__graph_find(g, a, (int32_t)b)] += c;
            g->w[dfm__graph_find(g, b, (int32_t)a)] += c;
        }
    }
    for (p = 0; p < g->start[g->nv]; p++)
        if (!(g->w[p] >= DFM__COTAN_FLOOR)) g->w[p] = DFM__COTAN_FLOOR;
}

/* ---------------------------------------------------------------------------------------------
   Section: deformation - a linear least-squares system on mesh vertices
   Energy sum_r |sum_{terms t of r} C_t x_{v(t)} - b_r|^2 + sum_{soft u} w^2 |x_u - target_u|^2,
   x_v a block of bs values per vertex and right-hand side. Known vertices are eliminated; the
   normal matrix over the unknowns is assembled from the rows (never forming the rectangular
   matrix) and factored once.
   --------------------------------------------------------------------------------------------- */

typedef struct dfm__lsq {
    size_t bs, nrhs, nv;
    size_t nrows;
    size_t *row_start;   /* nrows + 1: into the terms */
    int32_t *term_v;     /* vertex of each term */
    double *term_c;      /* bs x bs coefficients of each term, row-major */
    unsigned char *row_known; /* nrows: the row has a known vertex */
    size_t nu;           /* unknown vertices */
    const int32_t *unk;  /* nv: compact index of each unknown, -1 for known (shared) */
    const int32_t *unk_v; /* nu: vertex of each unknown (shared) */
    double soft_w2;      /* weight^2 of the soft rows (for unknowns with soft[v]) */
    const unsigned char *soft; /* nv or NULL: soft-constrained unknowns (shared) */
    dfm_csc normal;      /* the normal matrix, (bs nu) x (bs nu), lower */
    dfm_chol *chol;
    int chol_shared;     /* chol belongs to another system (the same matrix) */
    double *rhs, *x;     /* bs nu nrhs each: solve workspace */
} dfm__lsq;

static void dfm__lsq_free(dfm__lsq *s, const dfm_allocator *al)
{
    dfm__free(al, s->row_start);
    dfm__free(al, s->term_v);
    dfm__free(al, s->term_c);
    dfm__free(al, s->row_known);
    dfm_csc_free(&s->normal);
    if (!s->chol_shared) dfm_chol_free(s->chol);
    dfm__free(al, s->rhs);
    dfm__free(al, s->x);
    memset(s, 0, sizeof *s);
}

/* Room for nrows rows of nterms terms in all. */
static dfm_result dfm__lsq_alloc_rows(dfm__lsq *s, size_t nrows, size_t nterms, const dfm_allocator *al)
{
    dfm_result err = DFM_OK;
    s->nrows = nrows;
    s->row_start = (size_t *)dfm__alloc(al, nrows + 1, sizeof(size_t), &err);
    s->term_v = (int32_t *)dfm__alloc(al, nterms + 1, sizeof(int32_t), &err);
    s->term_c = (double *)dfm__alloc(al, (nterms + 1) * s->bs, s->bs * sizeof(double), &err);
    s->row_known = (unsigned char *)dfm__alloc(al, nrows + 1, 1, &err);
    if (err == DFM_OK) s->row_start[0] = 0;
    return err;
}

/* Vertex-level lower pattern of the normal matrix over the unknowns (the rows' cliques). */
static dfm_result dfm__lsq_pattern(const dfm__lsq *s, const dfm_allocator *al, dfm_csc *g)
{
    dfm_result err = DFM_OK;
    size_t nu = s->nu, r, t, u, cnt = 0, *vr_start = NULL;
    int32_t *vr = NULL, *mark = NULL, *list = NULL;
    memset(g, 0, sizeof *g);
    vr_start = (size_t *)dfm__alloc(al, nu + 2, sizeof(size_t), &err);
    mark = (int32_t *)dfm__alloc(al, nu + 1, sizeof(int32_t), &err);
    list = (int32_t *)dfm__alloc(al, nu + 1, sizeof(int32_t), &err);
    if (err != DFM_OK) goto done;
    memset(vr_start, 0, (nu + 2) * sizeof(size_t));
    for (t = 0; t < s->row_start[s->nrows]; t++)
        if (s->unk[s->term_v[t]] >= 0) vr_start[s->unk[s->term_v[t]] + 2]++;
    for (u = 0; u < nu; u++) vr_start[u + 2] += vr_start[u + 1];
    vr = (int32_t *)dfm__alloc(al, vr_start[nu + 1] + 1, sizeof(int32_t), &err);
    if (err != DFM_OK) goto done;
    for (r = 0; r < s->nrows; r++) /* vertex -> rows incidence */
        for (t = s->row_start[r]; t < s->row_start[r + 1]; t++)
            if (s->unk[s->term_v[t]] >= 0) vr[vr_start[s->unk[s->term_v[t]] + 1]++] = (int32_t)r;
    for (u = 0; u < nu; u++) mark[u] = -1;
    for (u = 0; u < nu; u++) { /* first pass: count column u's rows a >= u */
        size_t q;
        mark[u] = (int32_t)u;
        cnt++;
        for (q = vr_start[u]; q < vr_start[u + 1]; q++)
            for (t = s->row_start[vr[q]]; t < s->row_start[vr[q] + 1]; t++) {
                int32_t a = s->unk[s->term_v[t]];
                if (a > (int32_t)u && mark[a] != (int32_t)u) {
                    mark[a] = (int32_t)u;
                    cnt++;
                }
            }
    }
    err = dfm_csc_alloc(nu, nu, cnt, DFM_CSC_SYMMETRIC_LOWER, al, g);
    if (err != DFM_OK) goto done;
    for (u = 0; u < nu; u++) mark[u] = -1;
    cnt = 0;
    for (u = 0; u < nu; u++) { /* second pass: fill and sort */
        size_t q, m = 0;
        mark[u] = (int32_t)u;
        list[m++] = (int32_t)u;
        for (q = vr_start[u]; q < vr_start[u + 1]; q++)
            for (t = s->row_start[vr[q]]; t < s->row_start[vr[q] + 1]; t++) {
                int32_t a = s->unk[s->term_v[t]];
                if (a > (int32_t)u && mark[a] != (int32_t)u) {
                    mark[a] = (int32_t)u;
                    list[m++] = a;
                }
            }
        dfm__sort_i32(list, m);
        memcpy(g->row_index + cnt, list, m * sizeof(int32_t));
        memset(g->values + cnt, 0, m * sizeof(double));
        cnt += m;
        g->col_start[u + 1] = cnt;
    }
done:
    dfm__free(al, vr_start);
    dfm__free(al, vr);
    dfm__free(al, mark);
    dfm__free(al, list);
    if (err != DFM_OK) dfm_csc_free(g);
    return err;
}

/* position of row a in column b of a sorted CSC matrix (present by construction) */
static size_t dfm__csc_find(const dfm_csc *g, size_t b, int32_t a)
{
    size_t lo = g->col_start[b], hi = g->col_start[b + 1];
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (g->row_index[mid] < a) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* blocks[k] += C_p^T C_q (bs x bs, row-major), the contribution of one row to entry (a, b). */
static void dfm__add_ctc(size_t bs, const double *cp, const double *cq, double *blk)
{
    size_t i, j, k;
    for (i = 0; i < bs; i++)
        for (j = 0; j < bs; j++) {
            double sum = 0.0;
            for (k = 0; k < bs; k++) sum += cp[k * bs + i] * cq[k * bs + j];
            blk[i * bs + j] += sum;
        }
}

/* The normal matrix's values (vertex blocks) from the rows, the soft rows on the diagonal, then
   the block expansion for bs > 1. */
static dfm_result dfm__lsq_normal(dfm__lsq *s, const dfm_allocator *al)
{
    dfm_result err;
    dfm_csc g;
    size_t r, p, q, bs = s->bs, bb = bs * bs, u, k;
    double *blocks = NULL;
    err = dfm__lsq_pattern(s, al, &g);
    if (err != DFM_OK) return err;
    blocks = (double *)dfm__alloc(al, g.col_start[s->nu] + 1, bb * sizeof(double), &err);
    if (err != DFM_OK) goto done;
    memset(blocks, 0, g.col_start[s->nu] * bb * sizeof(double));
    for (r = 0; r < s->nrows; r++)
        for (p = s->row_start[r]; p < s->row_start[r + 1]; p++) {
            int32_t a = s->unk[s->term_v[p]];
            if (a < 0) continue;
            for (q = s->row_start[r]; q < s->row_start[r + 1]; q++) {
                int32_t b = s->unk[s->term_v[q]];
                if (b < 0 || b > a) continue;
                dfm__add_ctc(bs, s->term_c + p * bb, s->term_c + q * bb,
                             blocks + dfm__csc_find(&g, (size_t)b, a) * bb);
            }
        }
    for (u = 0; u < s->nu; u++)
        if (s->soft && s->soft[s->unk_v[u]])
            for (k = 0; k < bs; k++) blocks[g.col_start[u] * bb + k * bs + k] += s->soft_w2;
    if (bs == 1) {
        memcpy(g.values, blocks, g.col_start[s->nu] * sizeof(double));
        s->normal = g;
        memset(&g, 0, sizeof g);
    } else {
        err = dfm_block_expand(&g, bs, blocks, al, &s->normal);
    }
done:
    dfm__free(al, blocks);
    dfm_csc_free(&g);
    return err;
}

/* Progress of one step mapped into [base, base + span] of the whole call. */
typedef struct dfm__span {
    int (*progress)(void *user, float done);
    void *user;
    float base, span, last; /* last: what was reported, kept monotone */
} dfm__span;

static int dfm__span_call(void *user, float done)
{
    dfm__span *sp = (dfm__span *)user;
    float f = sp->base + sp->span * done;
    if (f > 1.0f) f = 1.0f;
    if (f > sp->last) sp->last = f;
    return sp->progress(sp->user, sp->last);
}

/* Normal matrix, analysis (nested dissection tried with the unknowns' positions) and factor. */
static dfm_result dfm__lsq_factor(dfm__lsq *s, const double *pos, int refine, const dfm_allocator *al, dfm__span *sp)
{
    dfm_result err = dfm__lsq_normal(s, al);
    dfm_chol_options co = dfm_chol_default_options();
    double *coords = NULL;
    size_t u, n = s->bs * s->nu;
    if (err == DFM_OK && !dfm__all_finite(s->normal.values, s->normal.col_start[n])) err = DFM_ERR_NOT_FINITE;
    if (err != DFM_OK) return err;
    coords = (double *)dfm__alloc(al, s->nu, 3 * sizeof(double), &err);
    s->rhs = (double *)dfm__alloc(al, n, s->nrhs * sizeof(double), &err);
    s->x = (double *)dfm__alloc(al, n, s->nrhs * sizeof(double), &err);
    if (err != DFM_OK) goto done;
    for (u = 0; u < s->nu; u++) memcpy(coords + 3 * u, pos + 3 * (size_t)s->unk_v[u], 3 * sizeof(double));
    co.block_size = s->bs;
    co.coords = coords;
    co.allocator = al;
    if (sp->progress) {
        co.progress = dfm__span_call;
        co.progress_user = sp;
    }
    sp->span *= 0.5f;
    err = dfm_chol_analyze(&s->normal, &co, &s->chol);
    sp->base += sp->span;
    if (err == DFM_OK) err = dfm_chol_factor(s->chol, &s->normal);
    if (s->chol) s->chol->progress = NULL; /* sp lives only during the setup */
    if (!refine) dfm_csc_free(&s->normal); /* kept only for iterative refinement */
    sp->base += sp->span;
done:
    dfm__free(al, coords);
    return err;
}

/* s has the same rows' matrix as from (factored): it uses from's factor. */
static dfm_result dfm__lsq_share(dfm__lsq *s, const dfm__lsq *from, const dfm_allocator *al)
{
    dfm_result err = DFM_OK;
    s->chol = from->chol;
    s->chol_shared = 1;
    s->rhs = (double *)dfm__alloc(al, s->bs * s->nu, s->nrhs * sizeof(double), &err);
    s->x = (double *)dfm__alloc(al, s->bs * s->nu, s->nrhs * sizeof(double), &err);
    return err;
}

/* One solve. X holds bs values per vertex and right-hand side, X[(q nv + v) bs + c]: read at the
   known vertices (their displacement) and at soft unknowns (their target), written at the
   unknowns. rowb: NULL (every b_r = 0) or bs x nrhs values per row, [(r nrhs + q) bs + c]. */
/* dfm__lsq_solve's right-hand side for bs = 1: each row's terms read once for all its columns
   (the same sums in the same order as the general loop, so the same bits). */
static void dfm__lsq_rhs1(dfm__lsq *s, const double *rowb, const double *X)
{
    size_t nr = s->nrhs, n = s->nu, nv = s->nv, r, t, q;
    double e[9];
    for (r = 0; r < s->nrows; r++) {
        if (!rowb && !s->row_known[r]) continue;
        for (q = 0; q < nr; q++) e[q] = rowb ? rowb[r * nr + q] : 0.0;
        for (t = s->row_start[r]; t < s->row_start[r + 1]; t++) {
            size_t v = (size_t)s->term_v[t];
            double c = s->term_c[t];
            if (s->unk[v] >= 0) continue;
            for (q = 0; q < nr; q++) e[q] -= c * X[q * nv + v];
        }
        for (t = s->row_start[r]; t < s->row_start[r + 1]; t++) {
            int32_t a = s->unk[s->term_v[t]];
            double c = s->term_c[t];
            if (a < 0) continue;
            for (q = 0; q < nr; q++) s->rhs[q * n + (size_t)a] += c * e[q];
        }
    }
}

static dfm_result dfm__lsq_solve(dfm__lsq *s, const double *rowb, double *X, int refine)
{
    size_t bs = s->bs, bb = bs * bs, nr = s->nrhs, n = bs * s->nu, nv = s->nv, r, t, q, i, k, u;
    double e[9];
    dfm_result err;
    memset(s->rhs, 0, n * nr * sizeof(double));
    for (u = 0; u < s->nu; u++)
        if (s->soft && s->soft[s->unk_v[u]])
            for (q = 0; q < nr; q++)
                for (k = 0; k < bs; k++)
                    s->rhs[q * n + u * bs + k] += s->soft_w2 * X[(q * nv + (size_t)s->unk_v[u]) * bs + k];
    if (bs == 1) dfm__lsq_rhs1(s, rowb, X);
    for (r = 0; r < s->nrows && bs > 1; r++) {
        if (!rowb && !s->row_known[r]) continue;
        for (q = 0; q < nr; q++) {
            for (k = 0; k < bs; k++) e[k] = rowb ? rowb[(r * nr + q) * bs + k] : 0.0;
            for (t = s->row_start[r]; t < s->row_start[r + 1]; t++) {
                const double *c = s->term_c + t * bb, *xk = X + (q * nv + (size_t)s->term_v[t]) * bs;
                if (s->unk[s->term_v[t]] >= 0) continue;
                for (i = 0; i < bs; i++)
                    for (k = 0; k < bs; k++) e[i] -= c[i * bs + k] * xk[k];
            }
            for (t = s->row_start[r]; t < s->row_start[r + 1]; t++) {
                const double *c = s->term_c + t * bb;
                int32_t a = s->unk[s->term_v[t]];
                if (a < 0) continue;
                for (i = 0; i < bs; i++)
                    for (k = 0; k < bs; k++) s->rhs[q * n + (size_t)a * bs + k] += c[i * bs + k] * e[i];
            }
        }
    }
    if (refine > 0) {
        err = dfm_chol_solve_refined(s->chol, &s->normal, s->rhs, s->x, nr, refine);
    } else { /* three right-hand sides at a time: the solve's fastest path */
        memcpy(s->x, s->rhs, n * nr * sizeof(double));
        for (q = 0, err = DFM_OK; q < nr && err == DFM_OK; q += 3)
            err = dfm_chol_solve(s->chol, s->x + q * n, nr - q < 3 ? nr - q : 3);
    }
    if (err != DFM_OK) return err;
    for (q = 0; q < nr; q++)
        for (u = 0; u < s->nu; u++)
            memcpy(X + (q * nv + (size_t)s->unk_v[u]) * bs, s->x + q * n + u * bs, bs * sizeof(double));
    return DFM_OK;
}

/* Appends a term to the row being built (s->row_start[r] .. terms so far). */
static void dfm__lsq_term(dfm__lsq *s, size_t *nterms, int32_t v, const double *c)
{
    s->term_v[*nterms] = v;
    memcpy(s->term_c + *nterms * s->bs * s->bs, c, s->bs * s->bs * sizeof(double));
    (*nterms)++;
}

/* Closes row r: its terms end at nterms; notes whether a term is on a known vertex. */
static void dfm__lsq_end_row(dfm__lsq *s, size_t r, size_t nterms)
{
    size_t t;
    s->row_start[r + 1] = nterms;
    s->row_known[r] = 0;
    for (t = s->row_start[r]; t < nterms; t++)
        if (s->unk[s->term_v[t]] < 0) s->row_known[r] = 1;
}

/* ---------------------------------------------------------------------------------------------
   Section: deformation - the object, its checks and the vertex sets
   --------------------------------------------------------------------------------------------- */

/* An allocator that counts the bytes held (and their peak) in front of the user's one. */
typedef struct dfm__meter {
    dfm_allocator inner;
    size_t bytes, peak;
} dfm__meter;

static void *dfm__meter_alloc(void *user, size_t size)
{
    dfm__meter *m = (dfm__meter *)user;
    unsigned char *p;
    if (size > (size_t)-1 - 16) return NULL;
    p = (unsigned char *)m->inner.alloc(m->inner.user, size + 16);
    if (!p) return NULL;
    memcpy(p, &size, sizeof size);
    m->bytes += size;
    if (m->bytes > m->peak) m->peak = m->bytes;
    return p + 16;
}

static void dfm__meter_free(void *user, void *ptr)
{
    dfm__meter *m = (dfm__meter *)user;
    size_t size;
    if (!ptr) return;
    memcpy(&size, (unsigned char *)ptr - 16, sizeof size);
    m->bytes -= size;
    m->inner.free(m->inner.user, (unsigned char *)ptr - 16);
}

struct dfm_deform {
    dfm__meter meter;
    dfm_allocator al;      /* the meter in front of the user's allocator */
    dfm_deform_options opt;
    size_t nv, nfree, nu, ne;
    double *pos;           /* nv x 3: the original positions */
    dfm__graph g;
    unsigned char *soft;   /* nv: soft-constrained unknowns (the handle with DFM_HANDLE_SOFT) */
    unsigned char *touched; /* nv: unknown, or a neighbour of one */
    int32_t *unk, *unk_v;  /* nv: compact unknown index or -1; nu: vertex of each unknown */
    dfm__lsq sys;          /* Laplacian or fitting system, or LRI's positions system */
    dfm__lsq fsys;         /* LRI's frames system */
    int32_t *edge;         /* LRI: 2 per edge with an unknown end (i < j) */
    double *edge_c;        /* LRI: 6 per edge, c_ij = F_i^T (x_j - x_i) and c_ji */
    double *frame;         /* LRI: nv x 9, the original frames (row-major, columns b1 b2 N) */
    double *X, *G, *rowb;  /* per-frame work: displacements, frame changes, position rows' b */
    double *S;             /* LRI with rigid_steps: 9 per unknown, the local fit's sums */
    int32_t *active;       /* the vertices in some row (unknowns and the known ones read) */
    size_t nactive;
    int scale_exp;         /* pos = the caller's positions times 2^-scale_exp (dfm__deform_rescale) */
};

DFMDEF dfm_deform_options dfm_deform_default_options(void)
{
    dfm_deform_options o;
    memset(&o, 0, sizeof o);
    o.handle_weight = 1.0;
    return o;
}

DFMDEF void dfm_deform_free(dfm_deform *d)
{
    dfm_allocator user;
    if (!d) return;
    user = d->meter.inner;
    dfm__lsq_free(&d->sys, &d->al);
    dfm__lsq_free(&d->fsys, &d->al);
    dfm__graph_free(&d->g, &d->al);
    dfm__free(&d->al, d->pos);
    dfm__free(&d->al, d->soft);
    dfm__free(&d->al, d->touched);
    dfm__free(&d->al, d->unk);
    dfm__free(&d->al, d->unk_v);
    dfm__free(&d->al, d->edge);
    dfm__free(&d->al, d->edge_c);
    dfm__free(&d->al, d->frame);
    dfm__free(&d->al, d->X);
    dfm__free(&d->al, d->G);
    dfm__free(&d->al, d->S);
    dfm__free(&d->al, d->rowb);
    dfm__free(&d->al, d->active);
    dfm__free(&user, d);
}

DFMDEF void dfm_deform_get_info(const dfm_deform *d, dfm_deform_info *info)
{
    dfm_chol_info ci;
    memset(info, 0, sizeof *info);
    if (!d) return;
    info->n_free = d->nfree;
    info->n_unknown = d->nu;
    info->bytes = d->meter.bytes + sizeof *d;
    dfm_chol_get_info(d->sys.chol, &ci);
    info->nnz_l = d->sys.chol ? ci.nnz_l : 0;
    if (d->fsys.chol && !d->fsys.chol_shared) {
        dfm_chol_get_info(d->fsys.chol, &ci);
        info->nnz_l += ci.nnz_l;
    }
}

/* Step 1: the arguments. */
static dfm_result dfm__deform_check(const double *pos, size_t nv, const uint32_t *idx, size_t nt,
                                    const unsigned char *roi, const unsigned char *handle,
                                    const dfm_deform_options *o)
{
    size_t v, nfree = 0;
    if (!pos || !idx || !roi || !handle || nv == 0 || nt == 0) return DFM_ERR_INVALID_ARGUMENT;
    if (o->method < DFM_METHOD_LAPLACIAN || o->method > DFM_METHOD_LRI) return DFM_ERR_INVALID_ARGUMENT;
    if (o->weights < DFM_WEIGHTS_UNIFORM || o->weights > DFM_WEIGHTS_COTAN) return DFM_ERR_INVALID_ARGUMENT;
    if (o->handle_constraint < DFM_HANDLE_HARD || o->handle_constraint > DFM_HANDLE_SOFT) return DFM_ERR_INVALID_ARGUMENT;
    if (o->frames < DFM_FRAMES_FIRST_EDGE || o->frames > DFM_FRAMES_MAX_ELEVATION) return DFM_ERR_INVALID_ARGUMENT;
    if (o->orthonormalize < DFM_ORTHO_NONE || o->orthonormalize > DFM_ORTHO_GRAM_SCHMIDT) return DFM_ERR_INVALID_ARGUMENT;
    if (o->refine_steps < 0 || o->rigid_steps < 0 || o->rigid_steps > 100) return DFM_ERR_INVALID_ARGUMENT;
    if (!dfm__finite(o->handle_weight) || o->handle_weight < 0.0) return DFM_ERR_BAD_VALUE;
    if (nv > DFM__MAX_N / 9 || nt > ((size_t)-1 >> 4) / 6) return DFM_ERR_TOO_LARGE;
    for (v = 0; v < 3 * nt; v++)
        if (idx[v] >= nv) return DFM_ERR_BAD_INDEX;
    for (v = 0; v < 3 * nv; v++)
        if (!dfm__finite(pos[v])) return DFM_ERR_BAD_VALUE;
    for (v = 0; v < nv; v++) {
        if (handle[v] && !roi[v]) return DFM_ERR_HANDLE_OUTSIDE_ROI;
        nfree += roi[v] && !handle[v];
    }
    return nfree == 0 ? DFM_ERR_EMPTY_ROI : DFM_OK;
}

/* Step 3: the unknowns (free vertices, and the handle's with soft constraints), and the vertices
   they touch (the rows that are not constant). */
static dfm_result dfm__deform_unknowns(dfm_deform *d, const unsigned char *roi, const unsigned char *handle)
{
    dfm_result err = DFM_OK;
    size_t v, p, nv = d->nv;
    int soft = d->opt.handle_constraint == DFM_HANDLE_SOFT;
    d->unk = (int32_t *)dfm__alloc(&d->al, nv, sizeof(int32_t), &err);
    d->unk_v = (int32_t *)dfm__alloc(&d->al, nv, sizeof(int32_t), &err);
    d->soft = (unsigned char *)dfm__alloc(&d->al, nv, 1, &err);
    d->touched = (unsigned char *)dfm__alloc(&d->al, nv, 1, &err);
    if (err != DFM_OK) return err;
    d->nu = d->nfree = 0;
    for (v = 0; v < nv; v++) {
        int u = roi[v] && (!handle[v] || soft) && d->g.start[v + 1] > d->g.start[v]; /* in a triangle */
        d->nfree += roi[v] && !handle[v];
        d->soft[v] = (unsigned char)(u && handle[v]);
        d->unk[v] = u ? (int32_t)d->nu : -1;
        if (u) d->unk_v[d->nu++] = (int32_t)v;
    }
    memset(d->touched, 0, nv);
    for (v = 0; v < nv; v++)
        if (d->unk[v] >= 0) {
            d->touched[v] = 1;
            for (p = d->g.start[v]; p < d->g.start[v + 1]; p++) d->touched[d->g.adj[p]] = 1;
        }
    return DFM_OK;
}

/* Step 4: no zero-area triangle may touch the system (its cotangents and normal are undefined). */
static dfm_result dfm__deform_check_triangles(const dfm_deform *d, const uint32_t *idx, size_t nt)
{
    size_t t;
    for (t = 0; t < nt; t++) {
        const uint32_t *f = idx + 3 * t;
        if ((d->touched[f[0]] || d->touched[f[1]] || d->touched[f[2]]) && dfm__degenerate(d->pos, f))
            return DFM_ERR_DEGENERATE_TRIANGLE;
    }
    return DFM_OK;
}

/* Step 5: every connected part of the unknowns must reach a known vertex or hold a soft one,
   else the energy has a null space (a free translation of that part). */
static dfm_result dfm__deform_check_constrained(const dfm_deform *d)
{
    dfm_result err = DFM_OK;
    size_t u, p;
    int32_t *stack = (int32_t *)dfm__alloc(&d->al, d->nu + 1, sizeof(int32_t), &err);
    unsigned char *seen = (unsigned char *)dfm__alloc(&d->al, d->nu + 1, 1, &err);
    if (err != DFM_OK) goto done;
    memset(seen, 0, d->nu);
    for (u = 0; u < d->nu && err == DFM_OK; u++) {
        size_t top = 0;
        int anchored = 0;
        if (seen[u]) continue;
        seen[u] = 1;
        stack[top++] = (int32_t)u;
        while (top > 0) {
            int32_t v = d->unk_v[stack[--top]];
            anchored |= d->soft[v];
            for (p = d->g.start[v]; p < d->g.start[v + 1]; p++) {
                int32_t a = d->unk[d->g.adj[p]];
                if (a < 0) anchored = 1;
                else if (!seen[a]) {
                    seen[a] = 1;
                    stack[top++] = a;
                }
            }
        }
        if (!anchored) err = DFM_ERR_UNCONSTRAINED;
    }
done:
    dfm__free(&d->al, stack);
    dfm__free(&d->al, seen);
    return err;
}

/* The system's shared vertex sets. */
static void dfm__lsq_init(dfm__lsq *s, const dfm_deform *d, size_t bs, size_t nrhs)
{
    memset(s, 0, sizeof *s);
    s->bs = bs;
    s->nrhs = nrhs;
    s->nv = d->nv;
    s->nu = d->nu;
    s->unk = d->unk;
    s->unk_v = d->unk_v;
    s->soft = d->soft;
    s->soft_w2 = d->opt.handle_weight * d->opt.handle_weight;
}

/* ---------------------------------------------------------------------------------------------
   Section: deformation - the three methods' rows
   --------------------------------------------------------------------------------------------- */

/* delta_i = x_i - sum_j w_ij x_j / W_i, the Laplacian coordinate with normalized weights. */
static void dfm__delta(const dfm_deform *d, size_t i, double *delta, double *wsum)
{
    size_t p, k;
    double W = 0.0;
    for (p = d->g.start[i]; p < d->g.start[i + 1]; p++) W += d->g.w[p];
    for (k = 0; k < 3; k++) delta[k] = d->pos[3 * i + k];
    for (p = d->g.start[i]; p < d->g.start[i + 1]; p++)
        for (k = 0; k < 3; k++) delta[k] -= d->g.w[p] / W * d->pos[3 * (size_t)d->g.adj[p] + k];
    *wsum = W;
}

/* Terms in the touched vertices' rows: a row per vertex with neighbours (closed 1-ring). */
static dfm_result dfm__ring_rows_alloc(dfm_deform *d, dfm__lsq *s)
{
    size_t v, rows = 0, terms = 0;
    for (v = 0; v < d->nv; v++)
        if (d->touched[v] && d->g.start[v + 1] > d->g.start[v]) {
            rows++;
            terms += 1 + d->g.start[v + 1] - d->g.start[v];
        }
    return dfm__lsq_alloc_rows(s, rows, terms, &d->al);
}

/* Method 1, plain Laplacian: row i is (L x')_i = delta_i, i.e. L d = 0 on the displacement. */
static dfm_result dfm__laplacian_rows(dfm_deform *d)
{
    size_t v, p, r = 0, nt = 0;
    dfm_result err;
    dfm__lsq_init(&d->sys, d, 1, 3);
    err = dfm__ring_rows_alloc(d, &d->sys);
    if (err != DFM_OK) return err;
    for (v = 0; v < d->nv; v++) {
        double W = 0.0, one = 1.0, c;
        if (!d->touched[v] || d->g.start[v + 1] == d->g.start[v]) continue;
        for (p = d->g.start[v]; p < d->g.start[v + 1]; p++) W += d->g.w[p];
        dfm__lsq_term(&d->sys, &nt, (int32_t)v, &one);
        for (p = d->g.start[v]; p < d->g.start[v + 1]; p++) {
            c = -d->g.w[p] / W;
            dfm__lsq_term(&d->sys, &nt, d->g.adj[p], &c);
        }
        dfm__lsq_end_row(&d->sys, r++, nt);
    }
    return DFM_OK;
}

static void dfm__skew(const double *a, double *m)
{
    m[0] = 0.0;   m[1] = -a[2]; m[2] = a[1];
    m[3] = a[2];  m[4] = 0.0;   m[5] = -a[0];
    m[6] = -a[1]; m[7] = a[0];  m[8] = 0.0;
}

static void dfm__mul33(const double *a, const double *b, double *r)
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* inverse of a symmetric positive definite 3x3 matrix (adjugate / determinant) */
static void dfm__inv33(const double *m, double *r)
{
    double det;
    int k;
    r[0] = m[4] * m[8] - m[5] * m[7];
    r[1] = m[2] * m[7] - m[1] * m[8];
    r[2] = m[1] * m[5] - m[2] * m[4];
    r[3] = m[5] * m[6] - m[3] * m[8];
    r[4] = m[0] * m[8] - m[2] * m[6];
    r[5] = m[2] * m[3] - m[0] * m[5];
    r[6] = m[3] * m[7] - m[4] * m[6];
    r[7] = m[1] * m[6] - m[0] * m[7];
    r[8] = m[0] * m[4] - m[1] * m[3];
    det = m[0] * r[0] + m[1] * r[3] + m[2] * r[6];
    for (k = 0; k < 9; k++) r[k] /= det;
}

/* The fit of vertex i's similarity, on centred coordinates q_j = x_j - c_i over J_i = {i} + N(i):
   s = sum q_j . x'_j / Q and h = S^-1 sum q_j x x'_j, S = sum (|q|^2 I - q q^T) (+ 1e-9 Q I
   against a collinear ring). Row block of x'_j: l_ij I - delta q_j^T / Q + [delta]x S^-1 [q_j]x. */
static void dfm__fit_block(const double *delta, const double *q, double Q, const double *Sinv, double lij,
                           double *blk)
{
    double a[9], b[9], t[9];
    int i, j;
    dfm__skew(delta, a);
    dfm__skew(q, b);
    dfm__mul33(a, Sinv, t);
    dfm__mul33(t, b, blk);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) blk[3 * i + j] += (i == j ? lij : 0.0) - delta[i] * q[j] / Q;
}

/* Method 2, transformation fitting: row i is (L x')_i - T_i(x') delta_i = 0, coupled x, y, z. */
static dfm_result dfm__fitting_rows(dfm_deform *d)
{
    size_t v, p, r = 0, nt = 0, k, m;
    dfm_result err;
    dfm__lsq_init(&d->sys, d, 3, 1);
    err = dfm__ring_rows_alloc(d, &d->sys);
    if (err != DFM_OK) return err;
    for (v = 0; v < d->nv; v++) {
        double delta[3], W, c[3] = {0, 0, 0}, q[3], Q = 0.0, S[9] = {0}, Sinv[9], blk[9];
        size_t nj = d->g.start[v + 1] - d->g.start[v] + 1;
        if (!d->touched[v] || nj == 1) continue;
        dfm__delta(d, v, delta, &W);
        for (k = 0; k < 3; k++) c[k] = d->pos[3 * v + k];
        for (p = d->g.start[v]; p < d->g.start[v + 1]; p++)
            for (k = 0; k < 3; k++) c[k] += d->pos[3 * (size_t)d->g.adj[p] + k];
        for (k = 0; k < 3; k++) c[k] /= (double)nj;
        for (m = 0; m < nj; m++) { /* m = 0: i itself, then the neighbours */
            size_t j = m == 0 ? v : (size_t)d->g.adj[d->g.start[v] + m - 1];
            dfm__sub3(d->pos + 3 * j, c, q);
            Q += dfm__dot3(q, q);
            for (k = 0; k < 9; k++) S[k] += (k % 4 == 0 ? dfm__dot3(q, q) : 0.0) - q[k / 3] * q[k % 3];
        }
        for (k = 0; k < 9; k += 4) S[k] += 1e-9 * Q;
        dfm__inv33(S, Sinv);
        for (m = 0; m < nj; m++) {
            size_t j = m == 0 ? v : (size_t)d->g.adj[d->g.start[v] + m - 1];
            double lij = m == 0 ? 1.0 : -d->g.w[d->g.start[v] + m - 1] / W;
            dfm__sub3(d->pos + 3 * j, c, q);
            dfm__fit_block(delta, q, Q, Sinv, lij, blk);
            dfm__lsq_term(&d->sys, &nt, (int32_t)j, blk);
        }
        dfm__lsq_end_row(&d->sys, r++, nt);
    }
    return DFM_OK;
}

/* Unit normals (area-weighted: the sum of the incident faces' cross products). */
static void dfm__normals(const dfm_deform *d, const uint32_t *idx, size_t nt, double *nrm)
{
    size_t t, v, k;
    memset(nrm, 0, 3 * d->nv * sizeof(double));
    for (t = 0; t < nt; t++) {
        const uint32_t *f = idx + 3 * t;
        double u[3], w[3], c[3];
        dfm__sub3(d->pos + 3 * (size_t)f[1], d->pos + 3 * (size_t)f[0], u);
        dfm__sub3(d->pos + 3 * (size_t)f[2], d->pos + 3 * (size_t)f[0], w);
        dfm__cross3(u, w, c);
        for (k = 0; k < 3; k++)
            for (v = 0; v < 3; v++) nrm[3 * (size_t)f[k] + v] += c[v];
    }
    for (v = 0; v < d->nv; v++) {
        double l = sqrt(dfm__dot3(nrm + 3 * v, nrm + 3 * v));
        for (k = 0; k < 3; k++) nrm[3 * v + k] = l > 0.0 ? nrm[3 * v + k] / l : (k == 2);
    }
}

/* The frame of vertex v: N, b1 = the unit tangent projection of the chosen neighbour edge (the
   first with a projection longer than 1e-6 of its edge; DFM_FRAMES_MAX_ELEVATION: the largest
   elevation angle, i.e. the most negative <e, N> / |e|, ties to the first), b2 = N x b1. */
static void dfm__frame(const dfm_deform *d, size_t v, const double *N, double *F)
{
    size_t p;
    double best = 2.0, b1[3] = {0, 0, 0}, b2[3];
    int k, found = 0;
    for (p = d->g.start[v]; p < d->g.start[v + 1]; p++) {
        double e[3], t[3], le, lt, key;
        dfm__sub3(d->pos + 3 * (size_t)d->g.adj[p], d->pos + 3 * v, e);
        le = sqrt(dfm__dot3(e, e));
        for (k = 0; k < 3; k++) t[k] = e[k] - dfm__dot3(e, N) * N[k];
        lt = sqrt(dfm__dot3(t, t));
        if (!(lt > 1e-6 * le)) continue;
        key = d->opt.frames == DFM_FRAMES_MAX_ELEVATION ? dfm__dot3(e, N) / le : 0.0;
        if (found && key >= best) continue;
        best = key;
        found = 1;
        for (k = 0; k < 3; k++) b1[k] = t[k] / lt;
    }
    if (!found) { /* no usable edge (not reached: such a vertex has a degenerate fan) */
        double a[3] = {1, 0, 0}, l;
        if (fabs(N[0]) > 0.9) a[0] = 0, a[1] = 1;
        for (k = 0; k < 3; k++) b1[k] = a[k] - dfm__dot3(a, N) * N[k];
        l = sqrt(dfm__dot3(b1, b1));
        for (k = 0; k < 3; k++) b1[k] /= l;
    }
    dfm__cross3(N, b1, b2);
    for (k = 0; k < 3; k++) {
        F[3 * k] = b1[k];
        F[3 * k + 1] = b2[k];
        F[3 * k + 2] = N[k];
    }
}

/* LRI's constants: the frames, the edges with an unknown end, c_ij = F_i^T (x_j - x_i), c_ji. */
static dfm_result dfm__lri_frames(dfm_deform *d, const uint32_t *idx, size_t nt)
{
    dfm_result err = DFM_OK;
    size_t v, p, e = 0, k;
    double *nrm = (double *)dfm__alloc(&d->al, d->nv, 3 * sizeof(double), &err);
    d->frame = (double *)dfm__alloc(&d->al, d->nv, 9 * sizeof(double), &err);
    if (err != DFM_OK) goto done;
    dfm__normals(d, idx, nt, nrm);
    for (v = 0; v < d->nv; v++) dfm__frame(d, v, nrm + 3 * v, d->frame + 9 * v);
    d->ne = 0;
    for (v = 0; v < d->nv; v++)
        for (p = d->g.start[v]; p < d->g.start[v + 1]; p++)
            d->ne += (size_t)d->g.adj[p] > v && (d->unk[v] >= 0 || d->unk[d->g.adj[p]] >= 0);
    d->edge = (int32_t *)dfm__alloc(&d->al, d->ne + 1, 2 * sizeof(int32_t), &err);
    d->edge_c = (double *)dfm__alloc(&d->al, d->ne + 1, 6 * sizeof(double), &err);
    d->rowb = (double *)dfm__alloc(&d->al, d->ne + 1, 3 * sizeof(double), &err);
    if (err != DFM_OK) goto done;
    for (v = 0; v < d->nv; v++)
        for (p = d->g.start[v]; p < d->g.start[v + 1]; p++) {
            size_t j = (size_t)d->g.adj[p];
            const double *Fi = d->frame + 9 * v, *Fj = d->frame + 9 * j;
            double x[3];
            if (j <= v || (d->unk[v] < 0 && d->unk[j] < 0)) continue;
            d->edge[2 * e] = (int32_t)v;
            d->edge[2 * e + 1] = (int32_t)j;
            dfm__sub3(d->pos + 3 * j, d->pos + 3 * v, x);
            for (k = 0; k < 3; k++) {
                d->edge_c[6 * e + k] = Fi[k] * x[0] + Fi[3 + k] * x[1] + Fi[6 + k] * x[2];
                d->edge_c[6 * e + 3 + k] = -(Fj[k] * x[0] + Fj[3 + k] * x[1] + Fj[6 + k] * x[2]);
            }
            e++;
        }
done:
    dfm__free(&d->al, nrm);
    return err;
}

/* Method 3, LRI: the frames system and the positions system (row per edge: sqrt(w_ij) (x'_j -
   x'_i) = sqrt(w_ij) (F'_i c_ij - F'_j c_ji) / 2, both directions of the edge in one row). The
   frames rows F'_j = F'_i R_ij, R_ij = F_i^T F_j, are solved in M_i = F'_i F_i^T: with F_i
   orthonormal, F'_j - F'_i R_ij = (M_j - M_i) F_j and |(M_j - M_i) F_j| = |M_j - M_i|, so the
   row is M_j - M_i = 0, one scalar row per edge for each of M's 9 entries. */
static dfm_result dfm__lri_rows(dfm_deform *d)
{
    dfm_result err;
    size_t e, ntf = 0, ntp = 0;
    dfm__lsq_init(&d->fsys, d, 1, 9);
    dfm__lsq_init(&d->sys, d, 1, 3);
    err = dfm__lsq_alloc_rows(&d->fsys, d->ne, 2 * d->ne, &d->al);
    if (err == DFM_OK) err = dfm__lsq_alloc_rows(&d->sys, d->ne, 2 * d->ne, &d->al);
    if (err != DFM_OK) return err;
    for (e = 0; e < d->ne; e++) {
        size_t i = (size_t)d->edge[2 * e], j = (size_t)d->edge[2 * e + 1];
        double one = 1.0, mone = -1.0, s, ms;
        dfm__lsq_term(&d->fsys, &ntf, (int32_t)j, &one);
        dfm__lsq_term(&d->fsys, &ntf, (int32_t)i, &mone);
        dfm__lsq_end_row(&d->fsys, e, ntf);
        s = sqrt(d->g.w[dfm__graph_find(&d->g, i, (int32_t)j)]);
        ms = -s;
        dfm__lsq_term(&d->sys, &ntp, (int32_t)j, &s);
        dfm__lsq_term(&d->sys, &ntp, (int32_t)i, &ms);
        dfm__lsq_end_row(&d->sys, e, ntp);
    }
    return DFM_OK;
}

/* The closest rotation (polar factor) by Newton's iteration X <- (g X + X^-T / g) / 2, scaled
   by g = |det X|^(-1/3) while far from converged (Higham 1986: a few steps instead of many). */
static void dfm__polar(double *X)
{
    int it, k, scale = 1;
    for (it = 0; it < 30; it++) {
        double inv[9], det, nx[9], diff = 0.0, size = 0.0, g;
        inv[0] = X[4] * X[8] - X[5] * X[7];
        inv[1] = X[5] * X[6] - X[3] * X[8];
        inv[2] = X[3] * X[7] - X[4] * X[6];
        inv[3] = X[2] * X[7] - X[1] * X[8];
        inv[4] = X[0] * X[8] - X[2] * X[6];
        inv[5] = X[1] * X[6] - X[0] * X[7];
        inv[6] = X[1] * X[5] - X[2] * X[4];
        inv[7] = X[2] * X[3] - X[0] * X[5];
        inv[8] = X[0] * X[4] - X[1] * X[3];
        det = X[0] * inv[0] + X[1] * inv[1] + X[2] * inv[2];
        if (!(fabs(det) > 1e-300)) return; /* singular: left as it is */
        g = scale ? pow(fabs(det), -1.0 / 3.0) : 1.0;
        for (k = 0; k < 9; k++) { /* inv holds the cofactors: X^-T = cof / det */
            nx[k] = 0.5 * (g * X[k] + inv[k] / (g * det));
            diff += (nx[k] - X[k]) * (nx[k] - X[k]);
            size += nx[k] * nx[k];
        }
        memcpy(X, nx, sizeof nx);
        if (diff <= 1e-30 * size) return;
        scale = diff > 1e-6 * size;
    }
}

/* Gram-Schmidt with N first: N' = N / |N|, b1' = b1 minus its N' part, normalized, b2' = N' x b1'. */
static void dfm__gram_schmidt(double *F)
{
    double b1[3], n[3], b2[3], l, dn;
    int k;
    for (k = 0; k < 3; k++) {
        b1[k] = F[3 * k];
        n[k] = F[3 * k + 2];
    }
    l = sqrt(dfm__dot3(n, n));
    if (!(l > 0.0)) return;
    for (k = 0; k < 3; k++) n[k] /= l;
    dn = dfm__dot3(b1, n);
    for (k = 0; k < 3; k++) b1[k] -= dn * n[k];
    l = sqrt(dfm__dot3(b1, b1));
    if (!(l > 0.0)) return;
    for (k = 0; k < 3; k++) b1[k] /= l;
    dfm__cross3(n, b1, b2);
    for (k = 0; k < 3; k++) {
        F[3 * k] = b1[k];
        F[3 * k + 1] = b2[k];
        F[3 * k + 2] = n[k];
    }
}

/* ---------------------------------------------------------------------------------------------
   Section: deformation - setup and solve
   --------------------------------------------------------------------------------------------- */

/* Step 8: the vertices the rows touch, so that a frame costs O(ROI), not O(mesh). */
static dfm_result dfm__active_list(dfm_deform *d)
{
    dfm_result err = DFM_OK;
    const dfm__lsq *sys[2];
    size_t k, t, v;
    unsigned char *mark = (unsigned char *)dfm__alloc(&d->al, d->nv, 1, &err);
    d->active = (int32_t *)dfm__alloc(&d->al, d->nv, sizeof(int32_t), &err);
    if (err != DFM_OK) {
        dfm__free(&d->al, mark);
        return err;
    }
    memset(mark, 0, d->nv);
    sys[0] = &d->sys;
    sys[1] = &d->fsys;
    for (k = 0; k < 2; k++)
        if (sys[k]->row_start)
            for (t = 0; t < sys[k]->row_start[sys[k]->nrows]; t++) mark[sys[k]->term_v[t]] = 1;
    d->nactive = 0;
    for (v = 0; v < d->nv; v++)
        if (mark[v]) d->active[d->nactive++] = (int32_t)v;
    dfm__free(&d->al, mark);
    return DFM_OK;
}

static int dfm__report(const dfm_deform_options *o, float done)
{
    return o->progress && o->progress(o->progress_user, done);
}

/* Steps 2-5: the mesh graph and every check, then the weights. */
static dfm_result dfm__deform_mesh(dfm_deform *d, const uint32_t *idx, size_t nt, const unsigned char *roi,
                                   const unsigned char *handle)
{
    dfm_result err = dfm__graph_build(idx, nt, d->nv, &d->al, &d->g);
    if (err == DFM_OK) err = dfm__check_manifold(idx, nt, &d->g);
    if (err == DFM_OK) err = dfm__check_welded(d->pos, &d->g, &d->al);
    if (err == DFM_OK) err = dfm__deform_unknowns(d, roi, handle);
    if (err == DFM_OK) err = dfm__deform_check_triangles(d, idx, nt);
    if (err == DFM_OK) err = dfm__deform_check_constrained(d);
    if (err == DFM_OK) dfm__edge_weights(d->pos, idx, nt, d->opt.weights, &d->g);
    return err;
}

/* Step 2a: the methods are scale-free, but their sums of squares (and FITTING's 3x3 inverses, of
   the sixth power of a 1-ring's size) are not: a mesh whose largest coordinate M (over vertices in
   triangles) is above 2^100 or below 2^-100 is scaled by the power of two that brings M into
   [0.5, 1) (exact), and the solves scale the targets and results back. Meshes in between keep
   their bits. */
static void dfm__deform_rescale(dfm_deform *d, const uint32_t *idx, size_t nt)
{
    double m = 0.0;
    size_t t, k;
    for (t = 0; t < 3 * nt; t++)
        for (k = 0; k < 3; k++)
            if (fabs(d->pos[3 * (size_t)idx[t] + k]) > m) m = fabs(d->pos[3 * (size_t)idx[t] + k]);
    d->scale_exp = 0;
    if (m > ldexp(1.0, 100) || (m > 0.0 && m < ldexp(1.0, -100))) {
        (void)frexp(m, &d->scale_exp);
        for (t = 0; t < 3 * d->nv; t++) d->pos[t] = ldexp(d->pos[t], -d->scale_exp);
    }
}

DFMDEF dfm_result dfm_deform_setup(const double *positions, size_t vertex_count, const uint32_t *indices,
                                   size_t triangle_count, const unsigned char *roi, const unsigned char *handle,
                                   const dfm_deform_options *options, dfm_deform **out)
{
    dfm_deform_options o = options ? *options : dfm_deform_default_options();
    dfm_allocator user = dfm__resolve_allocator(o.allocator);
    dfm_result err;
    dfm_deform *d;
    dfm__span sp;
    if (!out) return DFM_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (o.handle_weight == 0.0) o.handle_weight = 1.0;
    err = dfm__deform_check(positions, vertex_count, indices, triangle_count, roi, handle, &o); /* 1 */
    if (err != DFM_OK) return err;
    d = (dfm_deform *)dfm__alloc(&user, 1, sizeof *d, &err);
    if (!d) return err;
    memset(d, 0, sizeof *d);
    d->meter.inner = user;
    d->al.alloc = dfm__meter_alloc;
    d->al.free = dfm__meter_free;
    d->al.user = &d->meter;
    d->opt = o;
    d->nv = vertex_count;
    d->pos = (double *)dfm__alloc(&d->al, vertex_count, 3 * sizeof(double), &err);
    if (err == DFM_OK) {
        memcpy(d->pos, positions, vertex_count * 3 * sizeof(double));
        dfm__deform_rescale(d, indices, triangle_count);
        err = dfm__deform_mesh(d, indices, triangle_count, roi, handle); /* 2-5 */
    }
    if (err == DFM_OK && dfm__report(&o, 0.05f)) err = DFM_CANCELLED;
    if (err == DFM_OK) { /* 6: the method's rows */
        if (o.method == DFM_METHOD_LAPLACIAN) err = dfm__laplacian_rows(d);
        else if (o.method == DFM_METHOD_FITTING) err = dfm__fitting_rows(d);
        else {
            err = dfm__lri_frames(d, indices, triangle_count);
            if (err == DFM_OK) err = dfm__lri_rows(d);
        }
    }
    if (err == DFM_OK && dfm__report(&o, 0.1f)) err = DFM_CANCELLED;
    sp.progress = o.progress;
    sp.user = o.progress_user;
    sp.base = 0.1f;
    sp.last = 0.1f;
    sp.span = o.method == DFM_METHOD_LRI && (o.weights != DFM_WEIGHTS_UNIFORM || o.refine_steps) ? 0.45f : 0.9f;
    if (err == DFM_OK) err = dfm__lsq_factor(&d->sys, d->pos, o.refine_steps, &d->al, &sp); /* 7: factor once */
    sp.span = 0.45f;
    if (err == DFM_OK && o.method == DFM_METHOD_LRI) { /* uniform weights: the same matrix */
        if (o.weights == DFM_WEIGHTS_UNIFORM && !o.refine_steps) err = dfm__lsq_share(&d->fsys, &d->sys, &d->al);
        else err = dfm__lsq_factor(&d->fsys, d->pos, o.refine_steps, &d->al, &sp);
    }
    if (err == DFM_ERR_BAD_VALUE) err = DFM_ERR_NOT_FINITE; /* the input was finite (step 1): an overflow */
    if (err == DFM_OK) err = dfm__active_list(d); /* 8 */
    if (err == DFM_OK) {
        d->X = (double *)dfm__alloc(&d->al, vertex_count, 9 * sizeof(double), &err);
        d->G = (double *)dfm__alloc(&d->al, vertex_count, 9 * sizeof(double), &err);
        if (o.method == DFM_METHOD_LRI && o.rigid_steps > 0)
            d->S = (double *)dfm__alloc(&d->al, d->nu, 9 * sizeof(double), &err);
    }
    if (err == DFM_OK && dfm__report(&o, 1.0f)) err = DFM_CANCELLED;
    if (err != DFM_OK) {
        dfm_deform_free(d);
        return err;
    }
    *out = d;
    return DFM_OK;
}

/* The targets (and rotations) at the vertices the rows read must be finite. */
static dfm_result dfm__check_pose(const dfm_deform *d, const double *targets, const double *rot)
{
    size_t a, v, k;
    for (a = 0; a < d->nactive; a++) {
        v = (size_t)d->active[a];
        if (d->unk[v] >= 0 && !d->soft[v]) continue;
        for (k = 0; k < 3; k++)
            if (!dfm__finite(targets[3 * v + k])) return DFM_ERR_BAD_VALUE;
        if (rot)
            for (k = 0; k < 9; k++)
                if (!dfm__finite(rot[9 * v + k])) return DFM_ERR_BAD_VALUE;
    }
    return DFM_OK;
}

/* Known (and soft-target) displacements, bs = 1 (X[q nv + v]) or bs = 3 (X[3 v + q]). */
static void dfm__known_displacements(const dfm_deform *d, const double *targets, size_t bs)
{
    size_t a, v, q, nv = d->nv;
    for (a = 0; a < d->nactive; a++) {
        v = (size_t)d->active[a];
        if (d->unk[v] >= 0 && !d->soft[v]) continue;
        for (q = 0; q < 3; q++) {
            double x = (d->scale_exp ? ldexp(targets[3 * v + q], -d->scale_exp) : targets[3 * v + q]) - d->pos[3 * v + q];
            if (bs == 1) d->X[q * nv + v] = x;
            else d->X[3 * v + q] = x;
        }
    }
}

/* The one rotation R != I among the known (and soft) vertices' rotations, when every one of them
   is I or that R bit for bit (a rigid handle, fixed vertices in place); NULL otherwise. *one is
   set when every rotation is I. */
static const double *dfm__single_rotation(const dfm_deform *d, const double *rot, int *one)
{
    static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double *R = NULL;
    size_t a, v;
    *one = 1;
    if (!rot) return NULL;
    for (a = 0; a < d->nactive; a++) {
        const double *r;
        v = (size_t)d->active[a];
        if (d->unk[v] >= 0 && !d->soft[v]) continue;
        r = rot + 9 * v;
        if (!memcmp(r, id, sizeof id) || (R && !memcmp(r, R, sizeof id))) continue;
        if (R) return NULL;
        R = r;
        *one = 0;
    }
    return R;
}

/* phi into d->X[v] for the single-rotation case (1 where R, 0 where I; one scalar solve, taken
   with two zero columns beside it: the three-column solve is the fastest path). */
static dfm_result dfm__lri_phi(dfm_deform *d, const double *rot, const double *R)
{
    size_t a, v, nv = d->nv;
    dfm_result err;
    for (a = 0; a < d->nactive; a++) {
        v = (size_t)d->active[a];
        if (d->unk[v] >= 0 && !d->soft[v]) continue;
        d->X[v] = !memcmp(rot + 9 * v, R, 9 * sizeof(double));
        d->X[nv + v] = d->X[2 * nv + v] = 0.0;
    }
    d->fsys.nrhs = 3;
    err = dfm__lsq_solve(&d->fsys, NULL, d->X, d->opt.refine_steps);
    d->fsys.nrhs = 9;
    return err;
}

/* M - I of every active vertex into d->X (X[(3 c + k) nv + v]), the 9 right-hand sides. */
static dfm_result dfm__lri_rotation_field(dfm_deform *d, const double *rot)
{
    size_t a, v, k, nv = d->nv;
    for (a = 0; a < d->nactive; a++) {
        v = (size_t)d->active[a];
        if (d->unk[v] >= 0 && !d->soft[v]) continue;
        for (k = 0; k < 9; k++) d->X[k * nv + v] = rot[9 * v + k] - (k % 4 == 0);
    }
    return dfm__lsq_solve(&d->fsys, NULL, d->X, d->opt.refine_steps);
}

/* R = the turn about the unit axis u whose cosine and sine are c and s. */
static void dfm__rotation_cs(const double *u, double c, double s, double *R)
{
    double x = u[0], y = u[1], z = u[2], t = 1.0 - c;
    R[0] = t * x * x + c;     R[1] = t * x * y - s * z; R[2] = t * x * z + s * y;
    R[3] = t * x * y + s * z; R[4] = t * y * y + c;     R[5] = t * y * z - s * x;
    R[6] = t * x * z - s * y; R[7] = t * y * z + s * x; R[8] = t * z * z + c;
}

/* The unit axis and angle of a rotation, when the angle is clear of 0 and pi. */
static int dfm__axis_angle(const double *R, double *axis, double *angle)
{
    double c = 0.5 * (R[0] + R[4] + R[8] - 1.0), sn, l;
    axis[0] = R[7] - R[5];
    axis[1] = R[2] - R[6];
    axis[2] = R[3] - R[1];
    l = sqrt(dfm__dot3(axis, axis));
    sn = 0.5 * l;
    if (!(sn > 1e-6) || c < -1.0 + 1e-9) return 0;
    axis[0] /= l;
    axis[1] /= l;
    axis[2] /= l;
    *angle = atan2(sn, c);
    return 1;
}

/* LRI, step 1: the frames solve in M = F' F^T (known frames are R F, so M = R there); then
   F' = M F, orthonormalized as asked at the unknowns. When every known rotation is I or one R
   (about axis a by t), M = I + phi (R - I) exactly (the problem is linear), and its polar factor
   is the turn about a by atan2(phi sin t, 1 - phi + phi cos t) (M is that turn times a scaling
   in the plane normal to a). d->G gets F' - F of every vertex in a row. */
static dfm_result dfm__lri_solve_frames(dfm_deform *d, const double *rot)
{
    size_t a, v, c, k, m, nv = d->nv;
    int identity, analytic = 0;
    double axis[3], t = 0.0, ct = 1.0, st = 0.0;
    const double *R = dfm__single_rotation(d, rot, &identity);
    dfm_result err = identity ? DFM_OK : R ? dfm__lri_phi(d, rot, R) : dfm__lri_rotation_field(d, rot);
    if (err != DFM_OK) return err;
    if (R && d->opt.orthonormalize == DFM_ORTHO_POLAR) analytic = dfm__axis_angle(R, axis, &t);
    if (analytic) ct = cos(t), st = sin(t);
    for (a = 0; a < d->nactive; a++) {
        double M[9], Fp[9], phi;
        const double *F;
        int turned = 0;
        v = (size_t)d->active[a];
        F = d->frame + 9 * v;
        phi = R ? d->X[v] : 0.0;
        if (analytic && d->unk[v] >= 0) {
            double y = phi * st, x = 1.0 - phi + phi * ct, r = sqrt(x * x + y * y); /* the turn's cos, sin */
            dfm__rotation_cs(axis, r > 0.0 ? x / r : 1.0, r > 0.0 ? y / r : 0.0, M);
            turned = 1;
        } else {
            for (k = 0; k < 9; k++)
                M[k] = (identity ? 0.0 : R ? phi * (R[k] - (k % 4 == 0)) : d->X[k * nv + v]) + (k % 4 == 0);
        }
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) {
                double sum = 0.0;
                for (m = 0; m < 3; m++) sum += M[3 * c + m] * F[3 * m + k];
                Fp[3 * c + k] = sum;
            }
        if (d->unk[v] >= 0 && !turned && d->opt.orthonormalize == DFM_ORTHO_POLAR) dfm__polar(Fp);
        if (d->unk[v] >= 0 && d->opt.orthonormalize == DFM_ORTHO_GRAM_SCHMIDT) dfm__gram_schmidt(Fp);
        for (k = 0; k < 9; k++) d->G[9 * v + k] = Fp[k] - F[k];
    }
    return DFM_OK;
}

/* LRI, step 2: each edge row's right-hand side s (G_i c_ij - G_j c_ji) / 2 (the displacement
   form: the original frames reproduce x_j - x_i exactly). */
static void dfm__lri_position_rhs(dfm_deform *d)
{
    size_t e, q, m;
    for (e = 0; e < d->ne; e++) {
        size_t i = (size_t)d->edge[2 * e], j = (size_t)d->edge[2 * e + 1];
        const double *Gi = d->G + 9 * i, *Gj = d->G + 9 * j, *cij = d->edge_c + 6 * e, *cji = cij + 3;
        double s = d->sys.term_c[2 * e];
        for (q = 0; q < 3; q++) {
            double a = 0.0;
            for (m = 0; m < 3; m++) a += Gi[3 * q + m] * cij[m] - Gj[3 * q + m] * cji[m];
            d->rowb[3 * e + q] = 0.5 * s * a;
        }
    }
}

/* R <- Q R, Q the Cayley rotation of w: (I - W/2)^-1 (I + W/2), W = [w]x, the turn about w by
   2 atan(|w| / 2) (|w| to third order), orthogonal without a sine or a cosine:
   Q = I + f (K + h h^T - |h|^2 I), K = [h]x, h = w / 2, f = 2 / (1 + |h|^2). */
static void dfm__turn(const double *w, double *R)
{
    double h[3], hh, f, Q[9], T[9];
    int a, b;
    for (a = 0; a < 3; a++) h[a] = 0.5 * w[a];
    hh = dfm__dot3(h, h);
    f = 2.0 / (1.0 + hh);
    dfm__skew(h, Q);
    for (a = 0; a < 3; a++)
        for (b = 0; b < 3; b++) Q[3 * a + b] = (a == b) + f * (Q[3 * a + b] + h[a] * h[b] - (a == b) * hh);
    for (a = 0; a < 3; a++)
        for (b = 0; b < 3; b++) T[3 * a + b] = Q[3 * a] * R[b] + Q[3 * a + 1] * R[3 + b] + Q[3 * a + 2] * R[6 + b];
    memcpy(R, T, sizeof T);
}

/* The rotation R maximizing tr(R^T S) (the polar factor of S when det S > 0), from a start R
   close to it: R <- rot(w) R with w = sum_k R_k x S_k / |sum_k R_k . S_k| over the columns k
   (Mueller, Bender, Chentanez, Macklin 2016), until |w| < 1e-6, at most 4 rounds. Unlike
   Newton's iteration it needs no inverse (a flat ring's sum is of rank 2), and it commutes with
   rotations: S -> Q S, R -> Q R gives Q R. */
static void dfm__fit_rotation(const double *S, double *R)
{
    int it, c;
    for (it = 0; it < 4; it++) {
        double w[3] = {0, 0, 0}, dot = 0.0, r[3], s[3], x[3];
        for (c = 0; c < 3; c++) {
            r[0] = R[c], r[1] = R[3 + c], r[2] = R[6 + c];
            s[0] = S[c], s[1] = S[3 + c], s[2] = S[6 + c];
            dfm__cross3(r, s, x);
            w[0] += x[0], w[1] += x[1], w[2] += x[2];
            dot += dfm__dot3(r, s);
        }
        dot = fabs(dot) + 1e-300;
        for (c = 0; c < 3; c++) w[c] /= dot;
        if (!(dfm__dot3(w, w) > 1e-12)) return;
        dfm__turn(w, R);
    }
}

/* LRI's rigid step, local part: each unknown's rotation refitted to the solved positions, R_i =
   argmax tr(R^T S_i), S_i = sum_j w_ij e'_ij e_ij^T, e = x_j - x_i (the as-rigid-as-possible local
   step), started from the rotation it had (its polar factor on the first step, unless the frames
   were orthonormalized that way). The sums run over the edge list (e_ij = F_i c_ij, w_ij the
   positions row's coefficient squared; an edge adds the same product to both ends), with the
   displacements gathered three to a vertex first: each vertex is read once an edge, not once a
   coordinate, which is what this memory-bound loop costs. d->G gets R_i F_i - F_i, so that
   dfm__lri_position_rhs builds the global step's right-hand side. */
static void dfm__lri_fit_rotations(dfm_deform *d, int first)
{
    size_t a, e, u, k, c, nv = d->nv;
    double *D = d->X + 3 * nv; /* free after the frames solve */
    for (a = 0; a < d->nactive; a++) {
        size_t v = (size_t)d->active[a];
        for (k = 0; k < 3; k++) D[3 * v + k] = d->X[k * nv + v];
    }
    memset(d->S, 0, d->nu * 9 * sizeof(double));
    for (e = 0; e < d->ne; e++) {
        size_t i = (size_t)d->edge[2 * e], j = (size_t)d->edge[2 * e + 1];
        const double *F = d->frame + 9 * i, *cij = d->edge_c + 6 * e;
        double x[3], xp[3], w = d->sys.term_c[2 * e] * d->sys.term_c[2 * e], P[9];
        int32_t ui = d->unk[i], uj = d->unk[j];
        for (k = 0; k < 3; k++) {
            x[k] = F[3 * k] * cij[0] + F[3 * k + 1] * cij[1] + F[3 * k + 2] * cij[2];
            xp[k] = w * (x[k] + D[3 * j + k] - D[3 * i + k]);
        }
        for (k = 0; k < 9; k++) P[k] = xp[k / 3] * x[k % 3];
        if (ui >= 0)
            for (k = 0; k < 9; k++) d->S[9 * (size_t)ui + k] += P[k];
        if (uj >= 0)
            for (k = 0; k < 9; k++) d->S[9 * (size_t)uj + k] += P[k];
    }
    for (u = 0; u < d->nu; u++) {
        size_t i = (size_t)d->unk_v[u];
        const double *F = d->frame + 9 * i;
        double *G = d->G + 9 * i, R[9];
        for (c = 0; c < 3; c++) /* R_i = (G_i + F_i) F_i^T */
            for (k = 0; k < 3; k++)
                R[3 * c + k] = (G[3 * c] + F[3 * c]) * F[3 * k] + (G[3 * c + 1] + F[3 * c + 1]) * F[3 * k + 1] +
                               (G[3 * c + 2] + F[3 * c + 2]) * F[3 * k + 2];
        if (first && d->opt.orthonormalize != DFM_ORTHO_POLAR) dfm__polar(R);
        dfm__fit_rotation(d->S + 9 * u, R);
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++)
                G[3 * c + k] = R[3 * c] * F[k] + R[3 * c + 1] * F[3 + k] + R[3 * c + 2] * F[6 + k] - F[3 * c + k];
    }
}

/* unknown v's new coordinate q: its position plus its solved displacement, in the caller's scale */
static double dfm__solved(const dfm_deform *d, size_t v, size_t q)
{
    double x = d->pos[3 * v + q] + (d->sys.bs == 1 ? d->X[q * d->nv + v] : d->X[3 * v + q]);
    return d->scale_exp ? ldexp(x, d->scale_exp) : x;
}

DFMDEF dfm_result dfm_deform_solve(dfm_deform *d, const double *targets, const double *rotations, double *out)
{
    dfm_result err;
    size_t a, q, nv, bs;
    int k;
    if (!d || !targets || !out) return DFM_ERR_INVALID_ARGUMENT;
    nv = d->nv;
    bs = d->sys.bs;
    err = dfm__check_pose(d, targets, rotations);
    if (err == DFM_OK && d->opt.method == DFM_METHOD_LRI) {
        err = dfm__lri_solve_frames(d, rotations);
        if (err == DFM_OK) dfm__lri_position_rhs(d);
    }
    if (err != DFM_OK) return err;
    dfm__known_displacements(d, targets, bs);
    err = dfm__lsq_solve(&d->sys, d->opt.method == DFM_METHOD_LRI ? d->rowb : NULL, d->X, d->opt.refine_steps);
    for (k = 0; err == DFM_OK && d->opt.method == DFM_METHOD_LRI && k < d->opt.rigid_steps; k++) {
        dfm__lri_fit_rotations(d, k == 0);
        dfm__lri_position_rhs(d);
        err = dfm__lsq_solve(&d->sys, d->rowb, d->X, d->opt.refine_steps);
    }
    if (err == DFM_ERR_BAD_VALUE) err = DFM_ERR_NOT_FINITE; /* the pose was finite: an overflow */
    if (err != DFM_OK) return err;
    for (a = 0; a < d->nu; a++) /* out is written only when every new position is finite */
        for (q = 0; q < 3; q++)
            if (!dfm__finite(dfm__solved(d, (size_t)d->unk_v[a], q))) return DFM_ERR_NOT_FINITE;
    if (out != targets) memcpy(out, targets, 3 * nv * sizeof(double)); /* the known vertices */
    for (a = 0; a < d->nu; a++)
        for (q = 0; q < 3; q++) out[3 * (size_t)d->unk_v[a] + q] = dfm__solved(d, (size_t)d->unk_v[a], q);
    return DFM_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: deformation - ROI and pose helpers
   --------------------------------------------------------------------------------------------- */

DFMDEF dfm_result dfm_roi_rings(const uint32_t *indices, size_t triangle_count, size_t vertex_count, unsigned k,
                                unsigned char *mask, const dfm_allocator *allocator)
{
    dfm_allocator al = dfm__resolve_allocator(allocator);
    dfm_result err;
    dfm__graph g;
    unsigned char *next;
    size_t v, p, t;
    unsigned ring;
    if (!indices || !mask || vertex_count == 0) return DFM_ERR_INVALID_ARGUMENT;
    if (vertex_count > DFM__MAX_N || triangle_count > ((size_t)-1 >> 4) / 6) return DFM_ERR_TOO_LARGE;
    for (t = 0; t < 3 * triangle_count; t++)
        if (indices[t] >= vertex_count) return DFM_ERR_BAD_INDEX;
    err = dfm__graph_build(indices, triangle_count, vertex_count, &al, &g);
    if (err != DFM_OK) return err;
    next = (unsigned char *)dfm__alloc(&al, vertex_count, 1, &err);
    for (ring = 0; ring < k && err == DFM_OK; ring++) {
        memcpy(next, mask, vertex_count);
        for (v = 0; v < vertex_count; v++)
            if (mask[v])
                for (p = g.start[v]; p < g.start[v + 1]; p++) next[g.adj[p]] = 1;
        memcpy(mask, next, vertex_count);
    }
    dfm__free(&al, next);
    dfm__graph_free(&g, &al);
    return err;
}

/* binary min-heap of (distance, vertex) with lazy deletion */
static void dfm__heap_push(double *hd, int32_t *hv, size_t *n, double dist, int32_t v)
{
    size_t i = (*n)++;
    while (i > 0 && hd[(i - 1) / 2] > dist) {
        hd[i] = hd[(i - 1) / 2];
        hv[i] = hv[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    hd[i] = dist;
    hv[i] = v;
}

static void dfm__heap_pop(double *hd, int32_t *hv, size_t *n)
{
    size_t i = 0, m = --(*n);
    double dist = hd[m];
    int32_t v = hv[m];
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= m) break;
        if (c + 1 < m && hd[c + 1] < hd[c]) c++;
        if (hd[c] >= dist) break;
        hd[i] = hd[c];
        hv[i] = hv[c];
        i = c;
    }
    hd[i] = dist;
    hv[i] = v;
}

DFMDEF dfm_result dfm_roi_geodesic(const double *positions, size_t vertex_count, const uint32_t *indices,
                                   size_t triangle_count, const unsigned char *seeds, double radius,
                                   unsigned char *mask, const dfm_allocator *allocator)
{
    dfm_allocator al = dfm__resolve_allocator(allocator);
    dfm_result err;
    dfm__graph g;
    double *dist = NULL, *hd = NULL;
    int32_t *hv = NULL;
    size_t v, p, n = 0;
    if (!positions || !indices || !seeds || !mask || vertex_count == 0) return DFM_ERR_INVALID_ARGUMENT;
    if (!(radius == radius)) return DFM_ERR_BAD_VALUE;
    if (vertex_count > DFM__MAX_N || triangle_count > ((size_t)-1 >> 4) / 6) return DFM_ERR_TOO_LARGE;
    for (v = 0; v < 3 * triangle_count; v++)
        if (indices[v] >= vertex_count) return DFM_ERR_BAD_INDEX;
    for (v = 0; v < 3 * vertex_count; v++)
        if (!dfm__finite(positions[v])) return DFM_ERR_BAD_VALUE;
    err = dfm__graph_build(indices, triangle_count, vertex_count, &al, &g);
    if (err != DFM_OK) return err;
    dist = (double *)dfm__alloc(&al, vertex_count, sizeof(double), &err);
    hd = (double *)dfm__alloc(&al, g.start[vertex_count] + vertex_count, sizeof(double), &err);
    hv = (int32_t *)dfm__alloc(&al, g.start[vertex_count] + vertex_count, sizeof(int32_t), &err);
    if (err == DFM_OK) {
        for (v = 0; v < vertex_count; v++) {
            dist[v] = seeds[v] ? 0.0 : HUGE_VAL;
            if (seeds[v]) dfm__heap_push(hd, hv, &n, 0.0, (int32_t)v);
        }
        while (n > 0) { /* Dijkstra along the edges */
            double dv = hd[0];
            size_t u = (size_t)hv[0];
            dfm__heap_pop(hd, hv, &n);
            if (dv > dist[u] || dv > radius) continue;
            for (p = g.start[u]; p < g.start[u + 1]; p++) {
                double e[3], nd;
                size_t w = (size_t)g.adj[p];
                dfm__sub3(positions + 3 * w, positions + 3 * u, e);
                nd = dv + sqrt(dfm__dot3(e, e));
                if (!dfm__finite(nd)) { /* an edge (or path) longer than a double holds */
                    err = DFM_ERR_NOT_FINITE;
                    n = 0;
                    break;
                }
                if (nd < dist[w]) {
                    dist[w] = nd;
                    dfm__heap_push(hd, hv, &n, nd, (int32_t)w);
                }
            }
        }
        for (v = 0; v < vertex_count && err == DFM_OK; v++) mask[v] = dist[v] <= radius;
    }
    dfm__free(&al, dist);
    dfm__free(&al, hd);
    dfm__free(&al, hv);
    dfm__graph_free(&g, &al);
    return err;
}

DFMDEF dfm_result dfm_weld(const double *positions, size_t vertex_count, const uint32_t *indices,
                           size_t triangle_count, uint32_t *remap, uint32_t *out_indices,
                           const dfm_allocator *allocator)
{
    dfm_allocator al = dfm__resolve_allocator(allocator);
    dfm_result err = DFM_OK;
    dfm__vkey *keys;
    size_t v, t, first = 0;
    if (!positions || !remap || vertex_count == 0 || (triangle_count > 0 && (!indices || !out_indices)))
        return DFM_ERR_INVALID_ARGUMENT;
    if (vertex_count > DFM__MAX_N || triangle_count > ((size_t)-1 >> 4) / 6) return DFM_ERR_TOO_LARGE;
    for (t = 0; t < 3 * triangle_count; t++)
        if (indices[t] >= vertex_count) return DFM_ERR_BAD_INDEX;
    for (v = 0; v < 3 * vertex_count; v++)
        if (!dfm__finite(positions[v])) return DFM_ERR_BAD_VALUE;
    keys = (dfm__vkey *)dfm__alloc(&al, vertex_count, sizeof(dfm__vkey), &err);
    if (!keys) return err;
    for (v = 0; v < vertex_count; v++) {
        memcpy(keys[v].p, positions + 3 * v, 3 * sizeof(double));
        keys[v].v = (int32_t)v;
    }
    qsort(keys, vertex_count, sizeof *keys, dfm__cmp_vkey); /* equal positions: by index */
    for (v = 0; v < vertex_count; v++) {
        if (v > 0 && memcmp(keys[v].p, keys[first].p, 3 * sizeof(double)) != 0) first = v;
        remap[keys[v].v] = (uint32_t)keys[first].v;
    }
    for (t = 0; t < 3 * triangle_count; t++) out_indices[t] = remap[indices[t]];
    dfm__free(&al, keys);
    return DFM_OK;
}

DFMDEF void dfm_rotation(const double axis[3], double angle, double R[9])
{
    double l = sqrt(dfm__dot3(axis, axis)), u[3];
    u[0] = axis[0] / l;
    u[1] = axis[1] / l;
    u[2] = axis[2] / l;
    dfm__rotation_cs(u, cos(angle), sin(angle), R);
}

DFMDEF void dfm_pose_identity(const double *positions, size_t vertex_count, double *targets, double *rotations)
{
    size_t v;
    memcpy(targets, positions, 3 * vertex_count * sizeof(double));
    if (rotations)
        for (v = 0; v < vertex_count; v++) {
            double *r = rotations + 9 * v;
            memset(r, 0, 9 * sizeof(double));
            r[0] = r[4] = r[8] = 1.0;
        }
}

DFMDEF void dfm_pose_rigid(const double *positions, size_t vertex_count, const unsigned char *mask,
                           const double R[9], const double center[3], const double t[3], double *targets,
                           double *rotations)
{
    static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double zero[3] = {0, 0, 0}, *M = R ? R : id, *c = center ? center : zero, *tt = t ? t : zero;
    size_t v;
    int k;
    for (v = 0; v < vertex_count; v++) {
        double p[3];
        if (!mask[v]) continue;
        dfm__sub3(positions + 3 * v, c, p);
        for (k = 0; k < 3; k++) targets[3 * v + k] = dfm__dot3(M + 3 * k, p) + c[k] + tt[k];
        if (rotations) memcpy(rotations + 9 * v, M, 9 * sizeof(double));
    }
}

DFMDEF void dfm_pose_twist(const double *positions, size_t vertex_count, const unsigned char *mask,
                           const double point[3], const double axis[3], double angle, double *targets,
                           double *rotations)
{
    double R[9];
    dfm_rotation(axis, angle, R);
    dfm_pose_rigid(positions, vertex_count, mask, R, point, NULL, targets, rotations);
}

DFMDEF void dfm_pose_bend(const double *positions, size_t vertex_count, const unsigned char *mask,
                          const double base[3], const double axis[3], const double toward[3], double len,
                          double angle, double *targets, double *rotations)
{
    double a[3], b[3], n[3], R[9], h[3], t[3], la, lb, si, ve;
    int k;
    la = sqrt(dfm__dot3(axis, axis));
    for (k = 0; k < 3; k++) a[k] = axis[k] / la;
    for (k = 0; k < 3; k++) b[k] = toward[k] - dfm__dot3(toward, a) * a[k];
    lb = sqrt(dfm__dot3(b, b));
    for (k = 0; k < 3; k++) b[k] /= lb;
    dfm__cross3(a, b, n); /* turning a towards b is a rotation about a x b */
    dfm_rotation(n, angle, R);
    /* the arc's end: base + len (sin(angle) / angle) a + len ((1 - cos(angle)) / angle) b */
    si = fabs(angle) < 1e-8 ? 1.0 : sin(angle) / angle;
    ve = fabs(angle) < 1e-8 ? 0.5 * angle : (1.0 - cos(angle)) / angle;
    for (k = 0; k < 3; k++) {
        h[k] = base[k] + len * a[k];
        t[k] = base[k] + len * (si * a[k] + ve * b[k]) - h[k];
    }
    dfm_pose_rigid(positions, vertex_count, mask, R, h, t, targets, rotations);
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* DFM_IMPLEMENTATION_DONE */
#endif /* DFM_IMPLEMENTATION */
/*
------------------------------------------------------------------------------
This software is available under two licences; choose whichever you prefer.

------------------------------------------------------------------------------
ALTERNATIVE A - MIT License

Copyright (c) 2026 the detailed-surface graphics headers authors

Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:

The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.

------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)

This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.

In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication for the benefit of the public at large and to
the detriment of our heirs and successors. We intend this dedication to be an
overt act of relinquishment in perpetuity of all present and future rights to
this software under copyright law.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN
ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION
WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
*/
