#!/bin/sh
# gallery.sh BUILD_DIR OUT_DIR - what `make gallery` runs after `make demo`: each picture the demo wrote
# into OUT_DIR, made small enough to commit (build/thumbnail: at most 760 pixels wide and 60 KiB), as
# docs/NAME.png, the README's gallery. A picture the demo skipped (no glmark2-data) is named and kept.
set -e
B="$1"; OUT="$2"
docs=$(cd "$(dirname "$0")" && pwd)
made=0; missing=0
for name in dispmesh_bunny_views dispmesh_brick_views dispmesh_camel_views dispmesh_blobby_shuffled_views \
            terrain_desert terrain_vegetation terrain_mountain5 terrain_mountain6 \
            grass_mountain grass_wither grass_mingle grass_mesh_sphere grass_mesh_bunny \
            deform_fig4-4_cylinder_bend90 deform_fig4-4_cylinder_bend180 deform_fig4-4b_box_twist720 \
            deform_fig2-3_bunny_ear deform_fig2-3_bunny_ear_rigid5 \
            relief_fig6-9_cube_engraved relief_fig6-2_sheet relief_fig6-7_cylinder relief_baseline_sheet \
            erosion_fig5-2-1_torus_render erosion_fig5-2-2_reliefs_render erosion_fig5-2-3_letters_render \
            erosion_subdiv4_terrain_render \
            sphere_f16 bunny bunny_wire; do
  if [ -f "$OUT/$name.png" ]; then
    "$B/thumbnail" "$OUT/$name.png" "$docs/$name.png" --width 760 --max-bytes 61440
    made=$((made + 1))
  else
    echo "gallery: $OUT/$name.png was not written by make demo (see its messages): docs/$name.png kept as it was"
    missing=$((missing + 1))
  fi
done
echo "gallery: $made pictures in docs/, $missing missing"
