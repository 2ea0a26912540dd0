#!/usr/bin/env bash
# Makes the image variations of the loop-detection variation suite
# (docs/loop-detection.md): the frames of a sequence re-encoded, degraded or
# rescaled the way a camera, a codec or a pipeline changes them, so that the
# detector's precision is measured on images it was not tuned on.
#
#   scripts/make_variations.sh [-l] SOURCE_DIR OUT_DIR [CASE...]
#
# SOURCE_DIR holds the frames as 1.jpg, 2.jpg, ... (rtabmap-samples/samples).
# Each CASE becomes OUT_DIR/CASE/1.png, 2.png, ... (1.jpg, ... for the JPEG
# cases), the same frames in the same order, or OUT_DIR/CASE/video.mp4 for the
# video cases, at 1 frame per second (give detect-loops `--frequency 1` with
# it). Without CASE: every case.
# -l lists the cases with their part ("tuning" or "validation") and exits.
# Everything goes through ffmpeg (Debian package `ffmpeg`) with fixed thread counts
# and with fixed seeds, so the same ffmpeg build makes the same pixels.
# A case already made (OUT_DIR/CASE/.done) is not made again.
set -euo pipefail

# name | part | what (ffmpeg arguments between decoding the frames and writing them)
# The "tuning" cases chose the defaults; the "validation" cases were only
# measured afterwards.
cases=(
  "h264_crf18|tuning|video:libx264:18:"
  "h264_crf28|validation|video:libx264:28:"
  "h264_crf35|tuning|video:libx264:35:"
  "h265_crf18|validation|video:libx265:18:"
  "h265_crf28|tuning|video:libx265:28:"
  "h265_crf35|validation|video:libx265:35:"
  "jpeg_q8|validation|jpeg:8:"
  "jpeg_q16|tuning|jpeg:16:"
  "jpeg_q24|validation|jpeg:24:"
  "noise_8|validation|filter:noise=alls=8:allf=t:all_seed=11"
  "noise_16|tuning|filter:noise=alls=16:allf=t:all_seed=12"
  "gamma_0.6|tuning|filter:eq=gamma=0.6"
  "gamma_1.6|validation|filter:eq=gamma=1.6"
  "exposure_x1.5|tuning|filter:lutyuv=y=clip(val*1.5\\,0\\,255)"
  "exposure_x0.5|validation|filter:lutyuv=y=val*0.5"
  "blur_1.0|validation|filter:gblur=sigma=1.0"
  "blur_2.0|tuning|filter:gblur=sigma=2.0"
  "downscale_0.5|tuning|filter:scale=256:192:flags=area"
  "downscale_0.75|validation|filter:scale=384:288:flags=area"
  "upscale_1.5|tuning|filter:scale=768:576:flags=bicubic"
  "upscale_2|validation|filter:scale=1024:768:flags=bicubic"
  "noise_8+h264_crf28|tuning|video:libx264:28:noise=alls=8:allf=t:all_seed=13"
  "downscale_0.75+jpeg_q16|validation|jpeg:16:scale=384:288:flags=area"
  "exposure_x1.5+blur_1.0+h265_crf28|validation|video:libx265:28:lutyuv=y=clip(val*1.5\\,0\\,255),gblur=sigma=1.0"
  "gamma_1.6+upscale_1.5+h264_crf35|tuning|video:libx264:35:eq=gamma=1.6,scale=768:576:flags=bicubic"
)

list=0
if [ "${1:-}" = "-l" ]; then
  list=1
  shift
fi
if [ $list -eq 1 ]; then
  for c in "${cases[@]}"; do
    IFS='|' read -r name part _ <<<"$c"
    echo "$name $part"
  done
  exit 0
fi
[ $# -ge 2 ] || {
  echo "usage: $0 [-l] SOURCE_DIR OUT_DIR [CASE...]" >&2
  exit 2
}
source_dir=$1
out_dir=$2
shift 2
command -v ffmpeg >/dev/null 2>&1 || {
  echo "make_variations.sh: error: ffmpeg not found: install the Debian package ffmpeg" \
    "(scripts/install-deps.sh)" >&2
  exit 1
}
[ -f "$source_dir/1.jpg" ] || {
  echo "make_variations.sh: error: $source_dir has no frames 1.jpg, 2.jpg, ..." >&2
  exit 1
}
wanted=("$@")
if [ ${#wanted[@]} -eq 0 ]; then
  for c in "${cases[@]}"; do wanted+=("${c%%|*}"); done
fi

ffmpeg_quiet=(ffmpeg -nostdin -hide_banner -loglevel error -y -threads 1)
frames_in=(-framerate 1 -start_number 1 -i "$source_dir/%d.jpg")

make_case() {  # name spec
  local name=$1 spec=$2 dir="$out_dir/$1" kind rest codec crf filters
  [ -f "$dir/.done" ] && return 0
  rm -rf "$dir"
  mkdir -p "$dir"
  kind=${spec%%:*}
  rest=${spec#*:}
  case $kind in
    video)
      IFS=: read -r codec crf filters <<<"$rest"
      filters=${rest#"$codec:$crf:"}
      local video="$dir/video.mp4" codec_options=()
      [ "$codec" = libx265 ] && codec_options=(-x265-params "pools=1:frame-threads=1:log-level=error")
      [ "$codec" = libx264 ] && codec_options=(-x264-params "threads=3")
      "${ffmpeg_quiet[@]}" "${frames_in[@]}" ${filters:+-vf "$filters"} -c:v "$codec" \
        "${codec_options[@]}" -crf "$crf" -pix_fmt yuv420p "$video"
      ;;
    jpeg)
      IFS=: read -r crf filters <<<"$rest"
      filters=${rest#"$crf:"}
      "${ffmpeg_quiet[@]}" "${frames_in[@]}" ${filters:+-vf "$filters"} -c:v mjpeg -q:v "$crf" \
        -start_number 1 "$dir/%d.jpg"
      ;;
    filter)
      "${ffmpeg_quiet[@]}" "${frames_in[@]}" -vf "$rest" -start_number 1 "$dir/%d.png"
      ;;
  esac
  touch "$dir/.done"
}

for name in "${wanted[@]}"; do
  spec=
  for c in "${cases[@]}"; do
    IFS='|' read -r n _ s <<<"$c"
    [ "$n" = "$name" ] && spec=$s
  done
  [ -n "$spec" ] || {
    echo "make_variations.sh: error: unknown case $name (-l lists them)" >&2
    exit 2
  }
  make_case "$name" "$spec"
done
