#!/usr/bin/env bash
# Refreshes the teaching UI's vendored chart library (uPlot) from the npm
# registry: `npm ci` in crates/locus-serve/web installs exactly the version
# of package-lock.json (npm checks the tarball against the lock's sha512
# integrity), then its dist files are copied into crates/locus-serve/assets/vendor
# and their SHA-256 written to VENDORED, which the test
# `vendored_chart_library_matches_the_lock` checks (offline).
# To upgrade: change the version in web/package.json, `npm install` there,
# then run this script and commit web/package*.json and assets/vendor.
set -euo pipefail
cd "$(dirname "$0")/../crates/locus-serve"
(cd web && npm ci --no-audit --no-fund)
pkg=web/node_modules/uplot
version=$(node -p "require('./$pkg/package.json').version")
integrity=$(node -p "require('./web/package-lock.json').packages['node_modules/uplot'].integrity")
mkdir -p assets/vendor
cp "$pkg/dist/uPlot.iife.min.js" "$pkg/dist/uPlot.min.css" assets/vendor/
cp "$pkg/LICENSE" assets/vendor/uPlot.LICENSE
{
  echo "# Vendored by scripts/vendor-ui.sh from the npm registry; checked by locus-serve's tests."
  echo "package uplot $version $integrity"
  (cd assets/vendor && sha256sum uPlot.iife.min.js uPlot.min.css uPlot.LICENSE | sed 's/^/sha256 /')
} > assets/vendor/VENDORED
cat assets/vendor/VENDORED
