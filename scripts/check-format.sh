#!/usr/bin/env bash
# check-format.sh [--fix]: checks every tracked C++ file (*.h, *.cpp, *.cc) against .clang-format.
# Without --fix it changes nothing: it names each file clang-format would change and exits 1 if there is
# one (0 when all are formatted, 2 when clang-format is missing). With --fix it formats the files in place.
# Skipped: build trees, generated code (gen/, *.pb.h, *.pb.cc) and vendored code (third_party/, vendor/).
# The layout depends on clang-format's version: .clang-format is tuned for Debian's clang-format 14
# (CLANG_FORMAT=/path/to/clang-format to choose another binary).
set -euo pipefail
cd "$(dirname "$0")/.."
clang_format=${CLANG_FORMAT:-clang-format}
fix=0
case "${1:-}" in
  "") ;;
  --fix) fix=1 ;;
  *) echo "usage: $0 [--fix]" >&2; exit 2 ;;
esac
if ! command -v "$clang_format" >/dev/null; then
  echo "check-format: $clang_format not found (Debian: apt-get install clang-format)" >&2
  exit 2
fi
version=$("$clang_format" --version)
if [[ $version != *"version 14."* ]]; then
  echo "check-format: warning: .clang-format is tuned for clang-format 14, this is: $version" >&2
fi

files=()
while IFS= read -r -d '' f; do
  case "$f" in
    build*/* | */build/* | */gen/* | gen/* | *third_party/* | *vendor/* | *.pb.h | *.pb.cc) continue ;;
  esac
  files+=("$f")
done < <(git ls-files -z -- '*.h' '*.cpp' '*.cc')

if (( fix )); then
  printf '%s\0' "${files[@]}" | xargs -0 "$clang_format" -i
  echo "check-format: formatted ${#files[@]} files"
  exit 0
fi

# One clang-format run over all files; each violation is reported as "path:line:col: error: ...".
errors=$(printf '%s\0' "${files[@]}" | xargs -0 "$clang_format" --dry-run --Werror 2>&1 >/dev/null) || true
# Only paths of checked files count: an error in .clang-format itself is not a file to format.
bad=$(grep -oE '^[^:[:space:]]+:[0-9]+:[0-9]+: error' <<<"$errors" | cut -d: -f1 | sort -u |
  grep -Fx -f <(printf '%s\n' "${files[@]}") || true)
if [[ -z $bad ]]; then
  if [[ -n $errors ]]; then  # clang-format failed for another reason (a bad .clang-format, ...)
    echo "check-format: clang-format failed:" >&2
    echo "$errors" >&2
    exit 2
  fi
  echo "check-format: all ${#files[@]} files are formatted"
  exit 0
fi
echo "check-format: $(wc -l <<<"$bad") of ${#files[@]} files are not formatted (make format fixes them):" >&2
sed 's/^/  /' <<<"$bad" >&2
exit 1
