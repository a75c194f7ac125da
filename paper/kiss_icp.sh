#!/bin/sh
# KISS-ICP for `specular-reproduce --with-kiss-icp` (paper/reproduce/; it embeds and
# calls this script; it can also be run by hand).
#
#   kiss_icp.sh install VENV                      create VENV, pip install kiss-icp
#   kiss_icp.sh run VENV CONFIG FRAMES_DIR OUT    odometry over FRAMES_DIR/*.bin
#
# FRAMES_DIR holds KITTI-style .bin scans (float32 x y z intensity, sensor
# frame) named so that they sort in time order; the poses land in
# OUT/latest/<name>_poses_kitti.txt (one 3x4 row-major matrix per line).
set -eu
VERSION=1.3.0
cmd=$1
venv=$2
case "$cmd" in
install)
    if [ ! -x "$venv/bin/python" ]; then
        python3 -m venv "$venv"
    fi
    # PyYAML reads the --config file.
    if ! "$venv/bin/python" -c "import kiss_icp, yaml" 2>/dev/null; then
        "$venv/bin/pip" install --quiet --disable-pip-version-check "kiss-icp==$VERSION" pyyaml
    fi
    "$venv/bin/kiss_icp_pipeline" --version
    ;;
run)
    config=$3
    frames=$4
    out=$5
    mkdir -p "$out"
    export kiss_icp_out_dir="$out"
    exec "$venv/bin/kiss_icp_pipeline" --config "$config" "$frames"
    ;;
*)
    echo "usage: $0 install VENV | run VENV CONFIG FRAMES_DIR OUT" >&2
    exit 2
    ;;
esac
