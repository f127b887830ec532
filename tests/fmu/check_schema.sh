#!/usr/bin/env bash
# modelDescription.xml against the FMI schema of its version, from JOINTCOMP_SHARED/fmi-schema (the one
# setting for data the repository does not carry; .ci/run sets it). Without the schema: a named skip
# (exit 77, CTest's SKIP_RETURN_CODE).
#   check_schema.sh <2|3> <modelDescription.xml>
set -euo pipefail
version="$1" description="$2"
schema_relative="fmi-schema/fmi${version}/fmi${version}ModelDescription.xsd"
if [ -z "${JOINTCOMP_SHARED:-}" ]; then
  echo "skipped: the FMI $version schema not found: JOINTCOMP_SHARED is not set (a folder with $schema_relative)"
  exit 77
fi
schema="$JOINTCOMP_SHARED/$schema_relative"
if [ ! -f "$schema" ]; then
  echo "skipped: the FMI $version schema not found at $schema"
  exit 77
fi
xmllint --noout --schema "$schema" "$description"
