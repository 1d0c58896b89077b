#!/bin/sh
# viewer/build.sh SRC OUT: the page of `isochor view` as a static bundle in OUT/static (index.html,
# style.css, viewer.js: the page's modules and three.js in one script, which also runs from
# file://). The npm packages are the lockfile's (npm ci into OUT, not into the source tree),
# fetched once and again only when the lockfile changes. Without npm, or when npm cannot reach
# its registry, it says so and leaves the viewer unbuilt: the rest of isochor builds on.
set -eu
src=$1 out=$2
mkdir -p "$out/static"
cp "$src/package.json" "$src/package-lock.json" "$out/"
if [ ! -x "$out/node_modules/.bin/esbuild" ] || [ "$src/package-lock.json" -nt "$out/node_modules/.package-lock.json" ]; then
  if ! command -v npm > /dev/null 2>&1; then
    echo "viewer: npm not found: isochor view is not built (tools/install-deps.sh installs npm)"
    exit 0
  fi
  if ! (cd "$out" && npm ci --no-audit --no-fund --loglevel=error > npm.log 2>&1); then
    echo "viewer: npm ci failed ($out/npm.log): isochor view is not built"
    exit 0
  fi
fi
NODE_PATH="$out/node_modules" "$out/node_modules/.bin/esbuild" "$src/src/main.js" --bundle --minify --format=iife \
  --target=es2020 --log-level=warning --outfile="$out/static/viewer.js"
cp "$src/index.html" "$src/style.css" "$out/static/"
