#!/usr/bin/env bash
# Checks every `#include "pdamp/..."` in include/ and src/ against the table of layers in
# docs/architecture.md: a folder may include its own headers, the top-level
# include/pdamp/*.hpp, and the layers its row's last column names ("1–4, 6": numbers and
# ranges, "—" for none). A folder that is not in the table is an error too, so that the
# table stays complete. Internal headers (src/soft/neighbour_list.hpp, included as
# "soft/neighbour_list.hpp") follow the same table and are never included by a public
# header; which libraries see src/ at all is CMake's (src/CMakeLists.txt).
#
# Usage: tools/check-layers.sh
# Prints each include that breaks the rule (file:line). Exit 0 if none, 1 otherwise, 2 if
# the table cannot be read.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
doc="$root/docs/architecture.md"

declare -A layer allowed
# The table's rows: | N | `folder`, `folder` | library | what | may include |
while IFS='|' read -r _ number folders _ _ may _; do
  number=${number// /}
  [[ $number =~ ^[0-9]+$ ]] || continue
  set=" "
  may=${may// /}
  if [ "$may" != "—" ]; then
    IFS=',' read -ra items <<<"$may"
    for item in "${items[@]}"; do
      if [[ $item =~ ^([0-9]+)–([0-9]+)$ ]]; then
        for ((n = BASH_REMATCH[1]; n <= BASH_REMATCH[2]; ++n)); do set+="$n "; done
      elif [[ $item =~ ^[0-9]+$ ]]; then
        set+="$item "
      else
        echo "tools/check-layers.sh: $doc: layer $number may include '$item': not a number or a range N–M" >&2
        exit 2
      fi
    done
  fi
  for folder in $(grep -o '`[a-z_]*`' <<<"$folders" | tr -d '`'); do
    layer[$folder]=$number
    allowed[$folder]=$set
  done
done < <(sed -n '/^## Layers/,/^## /p' "$doc")
if [ ${#layer[@]} -eq 0 ]; then
  echo "tools/check-layers.sh: no table of layers under '## Layers' in $doc" >&2
  exit 2
fi

broken=0
for top in "$root/include/pdamp" "$root/src"; do
  for dir in "$top"/*/; do
    folder=$(basename "$dir")
    if [ -z "${layer[$folder]:-}" ]; then
      echo "${dir#"$root"/}: folder '$folder' is not in the table of layers in docs/architecture.md"
      broken=1
      continue
    fi
    while IFS=: read -r file line text; do
      shown=$(sed -E 's/.*#include "([^"]*)".*/\1/' <<<"$text")
      included=${shown#pdamp/}
      if [[ $shown == pdamp/* ]]; then
        [[ $included == */* ]] || continue  # a top-level header
      elif [ "$top" = "$root/include/pdamp" ]; then
        echo "${file#"$root"/}:$line: a public header includes $shown, an internal header of src/"
        broken=1
        continue
      fi
      target=${included%%/*}
      [ "$target" = "$folder" ] && continue
      if [ -z "${layer[$target]:-}" ]; then
        echo "${file#"$root"/}:$line: includes $shown, whose folder '$target' is not in the table of layers"
        broken=1
      elif [[ ${allowed[$folder]} != *" ${layer[$target]} "* ]]; then
        may=${allowed[$folder]# }
        echo "${file#"$root"/}:$line: $folder (layer ${layer[$folder]}) includes $shown (layer" \
          "${layer[$target]}, $target); it may include ${may:+layers }${may:-no other layer}"
        broken=1
      fi
    done < <(grep -rnE '#include "[a-z_]+/' "$dir" || true)
  done
done
exit "$broken"
