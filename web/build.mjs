// build.mjs [OUT_DIR]: bundles the browser viewer (src/) with esbuild into OUT_DIR (default dist/):
// index.html, viewer.css and one viewer.js holding three.js; nothing is fetched at run time.
import { build } from "esbuild";
import { copyFileSync, mkdirSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const out = process.argv[2] ?? join(here, "dist");
mkdirSync(out, { recursive: true });
await build({
  entryPoints: [join(here, "src/main.js")],
  bundle: true,
  minify: true,
  format: "iife",
  target: "es2020",
  outfile: join(out, "viewer.js"),
  logLevel: "warning",
});
for (const file of ["index.html", "viewer.css"]) copyFileSync(join(here, "src", file), join(out, file));
