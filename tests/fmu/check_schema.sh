#!/usr/bin/env bash
# modelDescription.xml against the FMI schema of its version, from JOINTCOMP_SHARED/fmi-schema (the one
# setting for data the repository does not carry; .ci/run sets it). Without the schema: a named skip
# (exit 77, CTest's SKIP_RETURN_CODE).
#   check_schema.sh <2|3> <modelDescription.xml>
set -euo pipefail
version="$1" description="$2"
source "$(dirname "$0")/../support/shared_data.sh"
require_shared_file schema "the FMI $version schema" "fmi-schema/fmi${version}/fmi${version}ModelDescription.xsd"
xmllint --noout --schema "$schema" "$description"
