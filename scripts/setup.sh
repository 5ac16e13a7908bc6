#!/usr/bin/env bash
# Installs the system packages aerial needs to build and to render on a
# machine without a GPU (Mesa's lavapipe CPU driver), plus the Khronos
# validation layers the test suite runs under. Idempotent: it only asks apt
# for what is missing, and does nothing when everything is present.
set -euo pipefail

packages=(
  mesa-vulkan-drivers   # lavapipe, the CPU Vulkan driver
  libvulkan1            # the Vulkan loader
  libvulkan-dev
  vulkan-validationlayers
  libshaderc-dev        # GLSL -> SPIR-V compiler used by build.rs
  glslang-dev           # static glslang libraries shaderc links against
  spirv-tools           # static SPIRV-Tools libraries shaderc links against
  pkg-config
  g++                   # nv-flip builds NVIDIA FLIP from C++ source
  valgrind              # `bench --metric instructions` counts the driver's instructions under callgrind
  assimp-testmodels     # real OBJ models (multi-group, JPEG textures, odd files) for tests/suite/real_models.rs
  neverball-common      # more OBJ models written by others, for tests/suite/model_corpus.rs
  glmark2-data          # the Stanford bunny and other OBJ models, for tests/suite/model_corpus.rs
  libx11-6              # `aerial view`: winit opens X11 windows through these, loaded at run time
  libx11-xcb1
  libxcursor1
  libxrandr2
  libxi6
  libxkbcommon-x11-0
  xvfb                  # a virtual X server: tests/suite/viewer.rs runs the viewer in it
  xauth
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all system packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO=sudo
  else
    echo "setup: not root and no sudo; run as root: apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
