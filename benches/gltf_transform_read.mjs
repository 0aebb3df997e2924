// glTF-Transform's read of glTF files, compressed or not: the peer of `benches/gltf_load.rs` (same protocol: one
// untimed read, then the median of 11). Needs, in the folder it runs from (outside the repository), `npm install
// @gltf-transform/core @gltf-transform/extensions draco3dgltf meshoptimizer`; its packages are found from there.
//   node PATH/TO/benches/gltf_transform_read.mjs FILE…
import { createRequire } from 'node:module';
import { pathToFileURL } from 'node:url';

const from = createRequire(`${process.cwd()}/`);
const load = async (name) => import(pathToFileURL(from.resolve(name)).href);
const { NodeIO } = await load('@gltf-transform/core');
const { ALL_EXTENSIONS } = await load('@gltf-transform/extensions');
const draco3d = (await load('draco3dgltf')).default;
const { MeshoptDecoder } = await load('meshoptimizer');

await MeshoptDecoder.ready;
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
  'draco3d.decoder': await draco3d.createDecoderModule(),
  'meshopt.decoder': MeshoptDecoder,
});
for (const file of process.argv.slice(2)) {
  await io.read(file);
  const times = [];
  for (let i = 0; i < 11; i++) {
    const t = performance.now();
    await io.read(file);
    times.push(performance.now() - t);
  }
  times.sort((a, b) => a - b);
  console.log(`glTF-Transform read ${file}: ${times[5].toFixed(1)} ms`);
}
