#!/usr/bin/env bash
# Lays out one FMU in a staging folder and zips it (FMI 2.0 and 3.0 share the layout; only the binary's
# platform folder differs):
#   modelDescription.xml
#   binaries/<platform>/<name>.so
#   resources/...       (robot.json, the parameter file, the URDF for reference)
#   documentation/...   (index.html first)
# usage: make-fmu.sh --staging <dir> --output <file.fmu> --model-description <xml> --binary <so>
#                    --platform <linux64|x86_64-linux> [--resource <file>[=<name>]]... [--documentation <file>[=<path>]]...
# The binary may already be in place (CMake builds it into the staging folder). The old .fmu is replaced,
# never updated (zip would otherwise keep files that are gone).
set -euo pipefail

staging= output= model_description= binary= platform=
resources=() documents=()
while [ $# -gt 0 ]; do
  case "$1" in
    --staging) staging="$2" ;;
    --output) output="$2" ;;
    --model-description) model_description="$2" ;;
    --binary) binary="$2" ;;
    --platform) platform="$2" ;;
    --resource) resources+=("$2") ;;
    --documentation) documents+=("$2") ;;
    *) echo "make-fmu.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
  shift 2
done
for name in staging output model_description binary platform; do
  if [ -z "${!name}" ]; then echo "make-fmu.sh: --${name//_/-} is required" >&2; exit 2; fi
done

# <source>[=<destination relative to the folder>] into a folder of the staging tree.
place() {
  local folder="$1" spec="$2" source destination
  source="${spec%%=*}"
  if [ "$source" = "$spec" ]; then destination="$(basename "$source")"; else destination="${spec#*=}"; fi
  mkdir -p "$(dirname "$staging/$folder/$destination")"
  cp "$source" "$staging/$folder/$destination"
}

rm -rf "$staging/resources" "$staging/documentation" "$staging/modelDescription.xml"
mkdir -p "$staging/binaries/$platform"
cp "$model_description" "$staging/modelDescription.xml"
library="$staging/binaries/$platform/$(basename "$binary")"
if [ "$(readlink -f "$binary")" != "$(readlink -f "$library")" ]; then cp "$binary" "$library"; fi
for spec in "${resources[@]}"; do place resources "$spec"; done
for spec in "${documents[@]}"; do place documentation "$spec"; done

output="$(readlink -f "$(dirname "$output")")/$(basename "$output")"
rm -f "$output"
(cd "$staging" && zip -q -X -r "$output" modelDescription.xml binaries resources documentation)
