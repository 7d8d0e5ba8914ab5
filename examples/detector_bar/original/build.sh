#!/bin/sh
# Builds the original WhyCode detector for the detector bar: the driver
# whycon_bar.cpp beside this script against the core of the whycon-ros
# sources (CWhycon, CCircleDetect, CNecklace, CTransformation; needs
# OpenCV's C++ headers: apt-get install libopencv-dev).
#
#   sh examples/detector_bar/original/build.sh PATH/TO/whycon-ros [OUT]
#
# OUT defaults to $CARGO_TARGET_DIR/whycon_bar (or target/whycon_bar), where
# the bar looks for it; WHYCON_BAR=path overrides.
set -eu
src=${1:?usage: build.sh PATH/TO/whycon-ros [OUT]}
here=$(dirname "$0")
out=${2:-${CARGO_TARGET_DIR:-$here/../../../target}/whycon_bar}
mkdir -p "$(dirname "$out")"
g++ -O2 -std=c++14 -I"$src/include" "$here/whycon_bar.cpp" \
    "$src"/src/whycon/CCircleDetect.cpp "$src"/src/whycon/CNecklace.cpp \
    "$src"/src/whycon/CRawImage.cpp "$src"/src/whycon/CTimer.cpp \
    "$src"/src/whycon/CTransformation.cpp "$src"/src/whycon/CWhycon.cpp \
    $(pkg-config --cflags --libs opencv4) -o "$out"
echo "built $out"
