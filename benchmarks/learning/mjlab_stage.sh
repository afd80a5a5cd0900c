#!/usr/bin/env bash
# Stage mjlab's packages for the GPU machine (which reaches no package registry), beside warpgym's own
# (../shared/hooks/stage-gpu-packages, run first: it empties .devstage). mjlab pins MuJoCo and MuJoCo Warp 3.11,
# so its packages unpack into a site of their own, $HOME/.cache/mjsite, put before warpgym's on mjlab's
# PYTHONPATH (benchmarks/learning/mjlab_side_by_side.py --mjlab-path).
#
# What is left out, unused by mjlab's env and training: wandb's 50 MB service binary (training logs to
# TensorBoard), MuJoCo's experimental extras and headers, jedi's type stubs, the YAM arm's meshes and
# imageio-ffmpeg's 165 MB ffmpeg (mjlab imports the package; IMAGEIO_FFMPEG_EXE names a stand-in).
# Writes .devstage/m1, m2, ...: send each in a device call (carry [".devstage/mK"], bash .devstage/mK/recv).
#
# usage: bash benchmarks/learning/mjlab_stage.sh        (in the project root; WG_PART_MB sets the part size)
set -euo pipefail
root=$(git rev-parse --show-toplevel)
cache=${XDG_CACHE_HOME:-$HOME/.cache}/devstage/mjlab-$(sha256sum "$root/benchmarks/learning/mjlab_gpu_wheels.txt" | cut -c1-12)
mkdir -p "$cache"
if [ ! -f "$cache/mjsite.tar.xz" ]; then
  rm -rf "$cache/whl" "$cache/site"; mkdir -p "$cache/whl" "$cache/site"
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 --platform manylinux1_x86_64 --platform manylinux_2_5_x86_64 \
    -d "$cache/whl" -r "$root/benchmarks/learning/mjlab_gpu_wheels.txt"
  for w in "$cache"/whl/*.whl; do python3 -m zipfile -e "$w" "$cache/site"; done
  rm -rf "$cache/site/wandb/bin" "$cache/site/mujoco/experimental" "$cache/site/mujoco/include" \
    "$cache/site/jedi/third_party" "$cache/site/mjlab/asset_zoo/robots/i2rt_yam/xmls/assets" \
    "$cache/site/imageio_ffmpeg/binaries"
  find "$cache/site" -name "*_test.py" -delete
  tar -C "$cache/site" -cf - . | xz -T0 -9 > "$cache/mjsite.tar.xz.tmp" && mv "$cache/mjsite.tar.xz.tmp" "$cache/mjsite.tar.xz"
  rm -rf "$cache/site" "$cache/whl"
fi
cd "$root"
mkdir -p .devstage; rm -rf .devstage/m[0-9]*
tree_mb=$(( $(git ls-files -z | xargs -0 stat -c %s | awk '{s+=$1} END {print s+0}') / 1048576 + 1 ))
part_mb=${WG_PART_MB:-$(( 62 - tree_mb < 56 ? 62 - tree_mb : 56 ))}
split -b $((part_mb * 1024 * 1024)) -d -a 2 "$cache/mjsite.tar.xz" .devstage/mpart
n=$(ls .devstage/mpart* | wc -l); sum=$(sha256sum "$cache/mjsite.tar.xz" | cut -c1-64); i=0
for f in .devstage/mpart*; do
  i=$((i + 1)); mkdir -p ".devstage/m$i"; mv "$f" ".devstage/m$i/"
  cat > ".devstage/m$i/recv" <<RECV
#!/usr/bin/env bash
# device side: keep this part of mjlab's packages; once all $n are here unpack them to \$HOME/.cache/mjsite
set -e
mkdir -p \$HOME/.cache/mjstage; cp "\$(dirname "\$0")"/mpart* \$HOME/.cache/mjstage/
if [ -f \$HOME/.cache/mjsite/.ready ] && [ "\$(cat \$HOME/.cache/mjsite/.ready)" = "$sum" ]; then echo "mjsite ready"; exit 0; fi
have=\$(ls \$HOME/.cache/mjstage/mpart* 2>/dev/null | wc -l)
if [ "\$have" -ge $n ]; then
  [ "\$(cat \$HOME/.cache/mjstage/mpart* | sha256sum | cut -c1-64)" = "$sum" ] || { echo "mjlab parts do not match; re-send all $n" >&2; rm -f \$HOME/.cache/mjstage/mpart*; exit 1; }
  rm -rf \$HOME/.cache/mjsite; mkdir -p \$HOME/.cache/mjsite
  cat \$HOME/.cache/mjstage/mpart* | xz -d -T0 | tar -x -C \$HOME/.cache/mjsite
  echo "$sum" > \$HOME/.cache/mjsite/.ready; echo "mjsite ready"
else
  echo "mjlab part received (\$have of $n)"
fi
RECV
  chmod +x ".devstage/m$i/recv"
done
du -sh .devstage/m*
echo "mjlab staged in $n parts: carry [\".devstage/mK\"] with command bash .devstage/mK/recv, K = 1..$n"
