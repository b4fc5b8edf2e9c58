#!/usr/bin/env bash
# Fails, naming the files, when a C++ file of the repository differs from what clang-format makes
# of it with the project's .clang-format (Debian's clang-format, installed by scripts/test.sh).
# To fix: clang-format -i FILE...
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
command -v clang-format >/dev/null || { echo "error: clang-format not found (apt-get install clang-format)" >&2; exit 1; }
unformatted=()
while IFS= read -r -d '' file; do
  clang-format --dry-run -Werror "$file" >/dev/null 2>&1 || unformatted+=("$file")
done < <(
  # The repository's files; outside a git checkout (an unpacked archive), every source folder's.
  git ls-files -z '*.cpp' '*.hpp' '*.h' '*.cc' 2>/dev/null ||
    find benchmarks common predictor producer tests trainer docs -type f \
      \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' -o -name '*.cc' \) \
      -not -path '*/node_modules/*' -print0
)
if [ ${#unformatted[@]} -gt 0 ]; then
  echo "error: ${#unformatted[@]} files differ from .clang-format (fix: clang-format -i FILE...):" >&2
  printf '  %s\n' "${unformatted[@]}" >&2
  exit 1
fi
echo "format: every C++ file follows .clang-format"
