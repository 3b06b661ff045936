#!/usr/bin/env bash
# Source-view gaps at 4x the working size for every trained run of the study, on evaluation photos (held-out rooms,
# courtyards, atria; 4 each): predict prints the share, this collects it into source_holes.csv. The runs were trained
# on dataset depth; here every photo goes through the demo's learned RGB prior (DEPTH_NET), the same for every run.
# VIEW_FLOOR (default 0: the checkpoint's own floor) is predict's --view-floor; its results go to
# source_holes_view<VIEW_FLOOR>.csv.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin="${BUILD_DIR:-build}"
depth_net="${DEPTH_NET:?set DEPTH_NET to a depth net, e.g. out/demo/depth/depth_net.safetensors}"
data=out/experiments/data
view_floor="${VIEW_FLOOR:-0}"
work=out/experiments/display/source_holes_view$view_floor
mkdir -p "$work"
list="$work/photos.txt"
{
  for s in ai_002_009 ai_002_010; do for f in 0000 0020; do
    echo "rooms_${s}_$f $data/hypersim/$s/images/scene_cam_00_final_preview/frame.$f.tonemap.jpg"; done; done
  for s in 0 1; do for f in IMG_0000 IMG_0010; do
    echo "courtyard_${s}_$f $data/eval/courtyard_colmap/scene_$s/images/$f.jpg"; done; done
  for s in 0 1; do for f in frame_00001 frame_00011; do
    echo "atrium_${s}_$f $data/eval/atrium_nerfstudio/scene_$s/images/$f.png"; done; done
} > "$list"
out=lab/2026-12-06-display-holes/source_holes.csv
[ "$view_floor" = 0 ] || out=lab/2026-12-06-display-holes/source_holes_view$view_floor.csv
echo "run,photo,holes_4x_percent" > "$out.tmp"
for run in full_s0 full_s1 floor035_s0 floor035_s1; do
  while read -r name photo; do
    share=$("$bin/infinisplat" predict --checkpoint "out/experiments/display/runs/$run/checkpoints/last.safetensors" \
      --image "$photo" --hfov 60 --view-floor "$view_floor" --set prior.type=learned --set "prior.learned_weights=$depth_net" \
      --out "$work/$run/$name.ply" | sed -n 's/^display *\([0-9.]*\)%.*/\1/p')
    echo "$run,$name,$share" >> "$out.tmp"
  done < "$list"
done
mv "$out.tmp" "$out"
