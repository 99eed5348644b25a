// Build the viewer's vendored scripts into cgamesh/viewer/assets from the pinned packages in
// package.json (run `npm ci` here first):  node build.mjs
//
//   three.min.js   three.js (the classes three-entry.js names, and OrbitControls) as one
//                  minified script defining the global THREE
//   ganja.min.js   ganja.js, minified (whitespace and syntax), defining the global Algebra
//   *.LICENSE      each package's licence, copied verbatim
//   MANIFEST.json  package versions and the sha256 of every file written
//
// Each script starts with a /*! ... */ banner naming its package, version and licence.
import { createHash } from "node:crypto";
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import * as esbuild from "esbuild";

const here = path.dirname(fileURLToPath(import.meta.url));
const out = path.resolve(here, "../../cgamesh/viewer/assets");
const pkg = (name) => JSON.parse(readFileSync(path.join(here, "node_modules", name, "package.json"), "utf8"));
const three = pkg("three");
const ganja = pkg("ganja.js");
const written = {};

function write(name, text) {
  writeFileSync(path.join(out, name), text);
  written[name] = createHash("sha256").update(text).digest("hex");
}

const threeBuild = await esbuild.build({
  entryPoints: [path.join(here, "three-entry.js")],
  bundle: true,
  minify: true,
  format: "iife",
  globalName: "THREE",
  target: "es2020",
  legalComments: "none",
  write: false,
  banner: { js: `/*! three.js ${three.version} (with OrbitControls) | ${three.license} License | Copyright 2010-2026 Three.js Authors | see three.LICENSE */` },
});
write("three.min.js", threeBuild.outputFiles[0].text);

const ganjaSource = readFileSync(path.join(here, "node_modules/ganja.js/ganja.js"), "utf8");
// ganja.js compiles the user's function text into code that names its own internals (Element,
// ...), so its identifiers must keep their names: whitespace and syntax are minified only.
const ganjaBuild = await esbuild.transform(ganjaSource, {
  minifyWhitespace: true,
  minifySyntax: true,
  target: "es2020",
  legalComments: "none",
  banner: `/*! ganja.js ${ganja.version} | ${ganja.license} License | Copyright (c) 2017 Steven De Keninck | see ganja.js.LICENSE */`,
});
write("ganja.min.js", ganjaBuild.code);

write("three.LICENSE", readFileSync(path.join(here, "node_modules/three/LICENSE"), "utf8"));
write("ganja.js.LICENSE", readFileSync(path.join(here, "node_modules/ganja.js/LICENSE"), "utf8"));
const manifest = {
  built_by: "tools/viewer/build.mjs",
  packages: {
    three: { version: three.version, license: three.license },
    "ganja.js": { version: ganja.version, license: ganja.license },
    esbuild: { version: pkg("esbuild").version },
  },
  sha256: written,
};
writeFileSync(path.join(out, "MANIFEST.json"), JSON.stringify(manifest, null, 2) + "\n");
console.log(`wrote ${Object.keys(written).join(", ")} and MANIFEST.json to ${out}`);
