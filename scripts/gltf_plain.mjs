// Writes a .glb again without meshopt compression, for scripts/compact_report.py: gltf-transform
// reads it (EXT_meshopt_compression / KHR_meshopt_compression decoded by meshoptimizer's
// decoder) and writes every buffer view plainly, the rest of the file as it was.
//
//   node scripts/gltf_plain.mjs IN.glb OUT.glb [TOOLS_DIR]   (default: .tools/npm, scripts/setup)
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const [input, output, toolsArgument] = process.argv.slice(2);
if (!output) {
  console.error('usage: node scripts/gltf_plain.mjs IN.glb OUT.glb [TOOLS_DIR]');
  process.exit(2);
}
const toolsDir = toolsArgument || process.env.KODAWARI_NODE_TOOLS ||
  path.join(path.dirname(fileURLToPath(import.meta.url)), '..', '.tools', 'npm');
const url = (p) => pathToFileURL(path.join(toolsDir, 'node_modules', p)).href;
let core, extensions, meshoptimizer;
try {
  core = await import(url('@gltf-transform/core/dist/index.js'));
  extensions = await import(url('@gltf-transform/extensions/dist/index.js'));
  meshoptimizer = await import(url('meshoptimizer/index.js'));
} catch (error) {
  console.error(`gltf_plain: cannot load @gltf-transform and meshoptimizer from ${toolsDir} (run scripts/setup): ${error.message}`);
  process.exit(1);
}
await meshoptimizer.MeshoptDecoder.ready;
const io = new core.NodeIO()
  .registerExtensions(extensions.ALL_EXTENSIONS)
  .registerDependencies({ 'meshopt.decoder': meshoptimizer.MeshoptDecoder });
const document = await io.read(input);
for (const extension of document.getRoot().listExtensionsUsed()) {
  if (/meshopt_compression$/.test(extension.extensionName)) extension.dispose();
}
await io.write(output, document);
