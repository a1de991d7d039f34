#!/bin/sh
# Build TChecker's tck-reach from its sources, outside this repository.
#
#   bench/build_tchecker.sh SRC_DIR BUILD_DIR
#
# SRC_DIR is a clone of https://github.com/ticktac-project/tchecker; BUILD_DIR is where cmake configures and
# builds (created if missing). Needs a C++17 compiler, cmake, flex, bison and Boost's headers; on Debian:
#   apt-get update && apt-get install -y cmake flex bison libboost-dev g++ make
# Prints the path of the built tck-reach on its last line (what bench/tchecker_bench.py takes as --tck-reach).
set -eu
if [ $# -ne 2 ]; then
    echo "usage: $0 SRC_DIR BUILD_DIR" >&2
    exit 2
fi
SRC=$(cd "$1" && pwd)
BUILD=$2
if [ ! -f "$SRC/CMakeLists.txt" ] || [ ! -d "$SRC/src/tck-reach" ]; then
    echo "$0: $SRC is not a TChecker source tree (no CMakeLists.txt or src/tck-reach)" >&2
    exit 2
fi
REPO=$(cd "$(dirname "$0")/.." && pwd)
case "$(cd "$(dirname "$BUILD")" 2>/dev/null && pwd)/" in
    "$REPO"/*) echo "$0: build outside the repository, not under $REPO" >&2; exit 2 ;;
esac
missing=""
for tool in cmake flex bison make c++; do
    command -v "$tool" >/dev/null 2>&1 || missing="$missing $tool"
done
[ -f /usr/include/boost/version.hpp ] || missing="$missing libboost-dev"
if [ -n "$missing" ]; then
    echo "$0: missing:$missing (Debian: apt-get update && apt-get install -y cmake flex bison libboost-dev g++ make)" >&2
    exit 2
fi
mkdir -p "$BUILD"
BUILD=$(cd "$BUILD" && pwd)
cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release
# Only the reachability tool: the unit tests need Catch2 and the docs Doxygen, neither of which the bench uses.
cmake --build "$BUILD" --target tck-reach -j "${JOBS:-2}"
found=$(find "$BUILD" -type f -name tck-reach -perm -u+x | head -n 1)
if [ -z "$found" ]; then
    echo "$0: the build finished but no tck-reach was found under $BUILD" >&2
    exit 1
fi
echo "$found"
