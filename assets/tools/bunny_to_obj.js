// Converts the npm package `bunny` (Mikola Lysenko; the Stanford bunny from the
// Stanford 3D Scanning Repository) to assets/meshes/bunny.obj.
//
//   cd /tmp && npm pack bunny && tar xzf bunny-1.0.1.tgz
//   node assets/tools/bunny_to_obj.js /tmp/package/index.js > assets/meshes/bunny.obj
//
// The package's index.js is plain CommonJS holding `positions` (an array of [x, y, z])
// and `cells` (0-based triangle indices); OBJ faces are 1-based. Positions are written
// as given (the package's own units and orientation, +Y up); scenes fit the size.
"use strict";
const path = require("path");
const src = process.argv[2];
if (!src) {
  console.error("usage: node bunny_to_obj.js path/to/bunny/index.js > bunny.obj");
  process.exit(2);
}
const bunny = require(path.resolve(src));
const out = [];
out.push("# Stanford bunny (Stanford 3D Scanning Repository), via npm package `bunny` 1.0.1");
out.push("# converted by assets/tools/bunny_to_obj.js; see assets/README.md");
out.push(`# ${bunny.positions.length} vertices, ${bunny.cells.length} triangles`);
for (const p of bunny.positions) out.push(`v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of bunny.cells) out.push(`f ${c[0] + 1} ${c[1] + 1} ${c[2] + 1}`);
process.stdout.write(out.join("\n") + "\n");
