#!/usr/bin/env bash
# The documentation check, as ctest runs it (entry `docs`):
#   tests/docs/check_docs.sh [REPO_ROOT]     (default: two folders up from this script)
# The repository carries its own documentation (docs/architecture.md is the source of truth), so:
#  1. every relative link in README.md, docs/*.md and the README.md of folders under src/
#     ([text](target) and [label]: target, outside code) names a file or folder inside the repository, and a #fragment names a heading of the
#     target Markdown file (GitHub's anchors: lower case, ASCII punctuation dropped, spaces to -);
#  2. no file of the repository names a path outside it: the founding design notes, the folder of
#     papers or the shared folder beside the checkout (the patterns below; docs/papers.md cites
#     the papers by author and year instead).
# Files are those tracked by git (tests/browser/node_modules excluded); outside a git checkout, every
# file under the root except .git, build*, out and node_modules. Exit 1 with one line per problem.
set -uo pipefail
export LC_ALL=C

here="$(cd "$(dirname "$0")" && pwd -P)"
root="$(cd "${1:-$here/../..}" && pwd -P)" || { echo "check_docs: no such folder: ${1:-}" >&2; exit 2; }
cd "$root" || exit 2
problems=0
problem() {
  echo "check_docs: $*" >&2
  problems=$((problems + 1))
}

# GitHub's heading anchors of a Markdown file, one a line (headings inside code fences skipped).
anchors() {
  awk '/^[ \t]*(```|~~~)/ { fence = !fence; next } !fence && /^#+[ \t]/' "$1" |
    sed -E 's/^#+[ \t]+//; s/[ \t]+#*[ \t]*$//' |
    tr '[:upper:]' '[:lower:]' |
    sed -E 's/[]!"#$%&'\''()*+,./:;<=>?@[\\^`{|}~]//g; s/ /-/g'
}

# 1. Links.
shopt -s nullglob
for md in README.md docs/*.md $(git ls-files "src/**/README.md" 2>/dev/null); do
  [ -f "$md" ] || continue
  dir="$(dirname "$md")"
  # Targets of inline links and reference definitions, with their line numbers; fenced blocks and
  # inline code spans are skipped (they show syntax, not links).
  while IFS=$'\t' read -r line target; do
    target="${target#<}"
    target="${target%>}"
    case "$target" in
      "" | [a-zA-Z]*://* | mailto:*) continue ;;
    esac
    path="${target%%#*}"
    fragment=""
    [ "$path" != "$target" ] && fragment="${target#*#}"
    if [ -z "$path" ]; then
      file="$md"
    else
      case "$path" in
        /*) problem "$md:$line: link '$target' is an absolute path; link files of the repository relatively"; continue ;;
      esac
      file="$dir/$path"
      resolved="$(realpath -m "$file")"
      case "$resolved/" in
        "$root"/*) ;;
        *) problem "$md:$line: link '$target' points outside the repository"; continue ;;
      esac
      if [ ! -e "$file" ]; then
        problem "$md:$line: link '$target': no such file in the repository"
        continue
      fi
    fi
    if [ -n "$fragment" ]; then
      case "$file" in
        *.md)
          if ! anchors "$file" | grep -qxF -- "$fragment"; then
            problem "$md:$line: link '$target': no heading with anchor #$fragment in $file"
          fi
          ;;
      esac
    fi
  done < <(awk '
    /^[ \t]*(```|~~~)/ { fence = !fence; next }
    fence { next }
    {
      s = $0
      gsub(/`[^`]*`/, "", s)
      if (match(s, /^[ \t]*\[[^]]+\]:[ \t]+[^ \t]+/)) {
        t = substr(s, RSTART, RLENGTH); sub(/^[ \t]*\[[^]]+\]:[ \t]+/, "", t)
        print NR "\t" t
        next
      }
      while (match(s, /\]\([^) \t]*/)) {
        print NR "\t" substr(s, RSTART + 2, RLENGTH - 2)
        s = substr(s, RSTART + RLENGTH)
      }
    }' "$md")
done

# 2. Paths outside the repository. The character classes keep this file from matching itself.
outside='[.][.]/shared/|paper[s]/|DESIG[N][.]md'
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  list() { git ls-files -z -- . ':(exclude)tests/browser/node_modules'; }
else
  list() {
    find . \( -name .git -o -name 'build*' -o -name out -o -name node_modules \) -prune -o -type f -print0 |
      sed -z 's|^\./||'
  }
fi
while IFS= read -r hit; do
  problem "$hit: names a path outside the repository (cite the paper by author and year, docs/papers.md, or link docs/architecture.md)"
done < <(list | xargs -0 -r grep -s -I -n -E -- "$outside" | cut -c1-200)

if [ "$problems" -gt 0 ]; then
  echo "check_docs: $problems problem(s)" >&2
  exit 1
fi
echo "check_docs: links in README.md, docs/*.md and src/**/README.md resolve; no file names a path outside the repository"
