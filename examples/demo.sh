#!/bin/sh
# demo.sh BUILD_DIR OUT_DIR - what `make demo` runs: every example on its default scene, outputs in OUT_DIR.
# Needs nothing beyond a C compiler: the meshes are generated; the bunny is added when glmark2-data is
# installed. Each step says what it wrote; scenes of headers that do not exist yet are named as such.
set -e
B="$1"; OUT="$2"
mkdir -p "$OUT"
rendered=0
"$B/gen_sphere" -f 16 -o "$OUT/sphere_f16.off" >/dev/null
"$B/meshconv" "$OUT/sphere_f16.off" -o "$OUT/sphere_f16.ply"
"$B/render_mesh" "$OUT/sphere_f16.off" -o "$OUT/sphere_f16.png" --wire --size 512
rendered=$((rendered + 1))
bunny=/usr/share/glmark2/models/bunny.obj
if [ -f "$bunny" ]; then
  "$B/meshconv" "$bunny" -o "$OUT/bunny.ply"
  "$B/render_mesh" "$bunny" -o "$OUT/bunny.png" --view front --size 768
  "$B/render_mesh" "$bunny" -o "$OUT/bunny_wire.png" --view front --wire --size 768
  rendered=$((rendered + 2))
else
  echo "demo: $bunny not found (apt-get install glmark2-data): bunny scenes skipped"
fi
# dispmesh.h: paper 000's base mesh + displacement map (its Figs 5.1.x): the generated brick down to its
# 12-face box, and the bunny down to 500 faces (each: _base.obj _disp.pfm _normal.png _recon.obj _views.png)
"$B/dispmesh" --brick --faces 12 --res 256 -o "$OUT/dispmesh_brick"
rendered=$((rendered + 1))
if [ -f "$bunny" ]; then
  "$B/dispmesh" "$bunny" --faces 500 --res 512 -o "$OUT/dispmesh_bunny"
  rendered=$((rendered + 1))
else
  echo "demo: $bunny not found (apt-get install glmark2-data): dispmesh bunny skipped"
fi
# ... and the camel of CGAL's data set, thin legs, down to 2000 faces: where the shell is too thin for an
# enclosing base, the fallback takes the collapses in cost order, so the base has no knots of small triangles
cgal=/usr/share/doc/libcgal-dev/data.tar.gz
if [ -f "$cgal" ] && tar xzf "$cgal" -O data/meshes/camel.off >"$OUT/camel.off" 2>/dev/null && [ -s "$OUT/camel.off" ]; then
  "$B/dispmesh" "$OUT/camel.off" --faces 2000 --res 1024 -o "$OUT/dispmesh_camel"
  rendered=$((rendered + 1))
else
  echo "demo: $cgal not found (apt-get install libcgal-demo): dispmesh camel skipped"
fi
# ... and CGAL's blobby with half of its triangles turned the other way, as exporters leave meshes:
# dm_orient turns them back (the tool says how many), and the base is blobby's own
if [ -f "$cgal" ] && tar xzf "$cgal" -O data/meshes/blobby-shuffled.off >"$OUT/blobby-shuffled.off" 2>/dev/null &&
   [ -s "$OUT/blobby-shuffled.off" ]; then
  "$B/dispmesh" "$OUT/blobby-shuffled.off" --faces 500 --res 512 -o "$OUT/dispmesh_blobby_shuffled"
  rendered=$((rendered + 1))
else
  echo "demo: $cgal not found (apt-get install libcgal-demo): dispmesh blobby-shuffled skipped"
fi
# subdiv4.h: paper 001's four terrain scenes (its Figs 3-6)
for scene in desert vegetation mountain5 mountain6; do
  "$B/terrain" --preset "$scene" -o "$OUT/terrain_$scene.png" && rendered=$((rendered + 1))
done
# deform.h: paper 004's figures, the three methods side by side (original | Laplacian | fitting | LRI):
# the cylinder bent 90 and 180 degrees (Fig 4-4), the box twisted through two turns (the second Fig 4-4),
# the bunny's ear dragged (Fig 2-3). 180 degrees and more take several steps (see deform --help).
"$B/deform" --cylinder --case bend --angle 90 -o "$OUT/deform_fig4-4_cylinder_bend90.png"
"$B/deform" --cylinder --case bend --angle 180 --steps 4 -o "$OUT/deform_fig4-4_cylinder_bend180.png"
"$B/deform" --box --case twist --angle 720 --steps 16 -o "$OUT/deform_fig4-4b_box_twist720.png"
rendered=$((rendered + 3))
if [ -f "$bunny" ]; then
  "$B/deform" "$bunny" --up y --region ball --case drag --shift 0.15 -o "$OUT/deform_fig2-3_bunny_ear.png"
  # the same drag with LRI followed by 5 as-rigid-as-possible steps (cotangent weights for every method)
  "$B/deform" "$bunny" --up y --region ball --case drag --shift 0.15 --weights cotan --rigid 5 \
    -o "$OUT/deform_fig2-3_bunny_ear_rigid5.png"
  rendered=$((rendered + 2))
else
  echo "demo: $bunny not found (apt-get install glmark2-data): deform bunny ear skipped"
fi
# texel.h: paper 002's withering grass: the mountain of 2.56M blades at wd 0, 0.30 and 0.917 (its
# Fig 13, 400x300 panels here; build/grass renders 800x600 by default), one patch's withering
# sequence, and mingling (its Fig 11)
"$B/grass" --scene mountain --size 400x300 -o "$OUT/grass_mountain.png"
"$B/grass" --scene wither --size 240x180 --frames 5 -o "$OUT/grass_wither.png"
"$B/grass" --scene mingle --size 200x150 --frames 5 -o "$OUT/grass_mingle.png"
rendered=$((rendered + 3))
# relief.h: paper 003's sketch fused into a rock example and relief-mapped on a cube (each: the render and
# a contact sheet example | sketch | fused height | normal map | render): a letter engraved in the asteroid
# height map of glmark2-data (its Fig 6-9 carves a character into a rock cube), white strokes embossed on a
# generated rock (its Figs 6-1/6-2) and on a cylinder with curved silhouettes (its Fig 6-7), and the
# distance-transform baseline on the same input
printf 'size 512 512\nwhite 80,420 160,300 260,250 380,120 440,90 width 10\nwhite 160,300 120,150 width 8\nwhite 260,250 330,330 420,360 width 8\n' > "$OUT/relief_strokes.txt"
asteroid=/usr/share/glmark2/textures/asteroid-height-map.png
if [ -f "$asteroid" ]; then
  "$B/relief" "$asteroid" text:R --crop 112,578,384 -o "$OUT/relief_fig6-9_cube_engraved.png" --sheet "$OUT/relief_fig6-9_sheet.png"
  rendered=$((rendered + 1))
else
  echo "demo: $asteroid not found (apt-get install glmark2-data): the asteroid relief skipped"
fi
"$B/relief" gen:rock "$OUT/relief_strokes.txt" -o "$OUT/relief_fig6-2_cube_embossed.png" --sheet "$OUT/relief_fig6-2_sheet.png" --height "$OUT/relief_fig6-2_height.png"
"$B/relief" gen:rock "$OUT/relief_strokes.txt" --cylinder -o "$OUT/relief_fig6-7_cylinder.png"
"$B/relief" gen:rock "$OUT/relief_strokes.txt" --emboss -o "$OUT/relief_baseline_emboss.png" --sheet "$OUT/relief_baseline_sheet.png"
rendered=$((rendered + 3))
# texel.h over a mesh shell (issue 19 point 4): a sphere's grass at wd 0.2 and 0.6, each tile's wd from
# a map over the mesh's tile coordinates (drier where the tile faces the sun), and the coarse bunny
"$B/grass" --mesh sphere --wd 0.2,0.6 --size 320x240 -o "$OUT/grass_mesh_sphere.png"
rendered=$((rendered + 1))
if [ -f /usr/share/glmark2/models/bunny.obj ]; then
  "$B/grass" --mesh /usr/share/glmark2/models/bunny.obj --wd 0.3 --size 320x240 -o "$OUT/grass_mesh_bunny.png"
  rendered=$((rendered + 1))
else
  echo "demo: /usr/share/glmark2/models/bunny.obj not found (apt-get install glmark2-data): grass bunny skipped"
fi
# erosion.h: paper 000 part B's wind erosion through the displacement map: its Fig 5.2.1, a torus of one
# material after 1 and 10 steps with the wind source marked (before | 1 | 10), seen from the side so
# that windward (orange: worn) and leeward show; Fig 5.2.2, a cylinder with bosses, the wind from -x
# (the left), the leeward side wearing less; Fig 5.2.3, a cylinder with the raised letters CGGM, CG
# hard and the rest soft; the bunny weathered; a subdiv4.h terrain (terrain --heights) weathered; a
# height map (a generated ridge field, tileable) weathered with a hard band painted from a mask
"$B/erode" --torus --steps 10 --wind -1,0,-0.3 --rate 0.02 --res 256 --size 320 --view 0.2,-1,0.9 \
  -o "$OUT/erosion_fig5-2-1_torus"
rendered=$((rendered + 1))
"$B/erode" --reliefs --steps 10 --wind 1,0,0 --rate 0.006 --res 256 --size 320 --render-steps 3,10 --view 0,-1,0.3 \
  -o "$OUT/erosion_fig5-2-2_reliefs"
rendered=$((rendered + 1))
"$B/erode" --letters --steps 10 --wind 1,0,0 --rate 0.006 --res 256 --size 320 --render-steps 3,10 --view -1,0,0.25 \
  -o "$OUT/erosion_fig5-2-3_letters"
rendered=$((rendered + 1))
"$B/terrain" --preset vegetation --levels 5 --size 320 -o "$OUT/erosion_subdiv4_terrain_in.png" \
  --heights "$OUT/erosion_subdiv4_terrain_in.pfm"
"$B/erode" "$OUT/erosion_subdiv4_terrain_in.pfm" --steps 20 --wind 1,0.4,-0.6 --rate 0.0015 --render-steps 5,20 \
  --size 320 -o "$OUT/erosion_subdiv4_terrain"
rendered=$((rendered + 1))
if [ -f /usr/share/glmark2/models/bunny.obj ]; then
  "$B/erode" /usr/share/glmark2/models/bunny.obj --steps 10 --wind -1,-0.3,-0.5 --rate 0.004 --res 256 --size 320 \
    -o "$OUT/erosion_bunny"
  rendered=$((rendered + 1))
else
  echo "demo: /usr/share/glmark2/models/bunny.obj not found (apt-get install glmark2-data): erosion bunny skipped"
fi
awk 'BEGIN { n = 256; printf "P2\n%d %d\n65535\n", n, n; for (y = 0; y < n; y++) { for (x = 0; x < n; x++) {
  h = 0.5 + 0.25 * sin(6.2832 * 3 * x / n) * cos(6.2832 * 2 * y / n) + 0.1 * sin(6.2832 * (9 * x + 4 * y) / n);
  printf "%d ", int(h * 65535) } printf "\n" } }' > "$OUT/erosion_terrain_in.pgm"
awk 'BEGIN { n = 64; printf "P2\n%d %d\n255\n", n, n; for (y = 0; y < n; y++) { for (x = 0; x < n; x++) printf "%d ", (x >= 24 && x < 40) * 255; printf "\n" } }' \
  > "$OUT/erosion_terrain_mask.pgm"
"$B/erode" "$OUT/erosion_terrain_in.pgm" --steps 20 --wind 1,0.4,-0.6 --wrap --rate 0.0015 --height-scale 0.15 \
  --material "$OUT/erosion_terrain_mask.pgm" --render-steps 20 --size 320 -o "$OUT/erosion_terrain"
rendered=$((rendered + 1))
for h in dispmesh.h erosion.h texel.h subdiv4.h deform.h; do
  [ -f "$h" ] || echo "demo: $h does not exist yet: its scenes are not rendered"
done
echo "demo: rendered $rendered scenes into $OUT/ (see the RESULT lines above)"
