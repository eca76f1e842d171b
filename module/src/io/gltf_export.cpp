// glTF 2.0 binary export of a RoamView's per-patch meshes with tinygltf.
#include "ridgeline/gltf_export.h"

#include <tiny_gltf.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>

#include "format.h"

namespace ridgeline::io {

namespace {

// Appends raw bytes to the single buffer (4-byte aligned) and returns a buffer view index.
int add_view(tinygltf::Model& model, const void* data, std::size_t bytes, int target) {
  auto& buf = model.buffers[0].data;
  while (buf.size() % 4) buf.push_back(0);
  tinygltf::BufferView bv;
  bv.buffer = 0;
  bv.byteOffset = buf.size();
  bv.byteLength = bytes;
  bv.target = target;
  const auto* p = static_cast<const unsigned char*>(data);
  buf.insert(buf.end(), p, p + bytes);
  model.bufferViews.push_back(bv);
  return static_cast<int>(model.bufferViews.size() - 1);
}

}  // namespace

Status write_glb(RoamView& view, const std::string& path, const GltfExportOptions& options) {
  if (path.empty()) return Error{"glTF export: empty output path"};
  {  // A missing folder is named as such (the writer would only fail at the rename).
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code ec;
    const auto type = std::filesystem::status(folder, ec).type();
    if (!folder.empty() && type == std::filesystem::file_type::not_found)
      return Error{fmt("glTF export '%s': the folder '%s' does not exist", path.c_str(),
                       folder.string().c_str())};
    if (!folder.empty() && !ec && type != std::filesystem::file_type::directory)
      return Error{
          fmt("glTF export '%s': '%s' is not a folder", path.c_str(), folder.string().c_str())};
  }
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "Ridgeline";
  model.buffers.resize(1);
  tinygltf::Scene scene;
  const Landscape& l = view.landscape();
  std::vector<float> pos, nrm;
  std::vector<std::uint32_t> idx, remap;
  for (std::uint32_t p = 0; p < l.patch_count(); ++p) {
    const PatchMesh& pm = view.patch_mesh(p);
    // Keep the triangles asked for, and only the vertices they use.
    pos.clear();
    nrm.clear();
    idx.clear();
    remap.assign(pm.vertices.size(), std::numeric_limits<std::uint32_t>::max());
    for (std::size_t t = 0; 3 * t + 2 < pm.indices.size(); ++t) {
      // Unused slots and triangles over the padding are degenerate (0, 0, 0): the mesh ends on
      // the border of the sampled data.
      if (pm.indices[3 * t] == pm.indices[3 * t + 1]) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = pm.indices[3 * t + k];
        if (remap[v] == std::numeric_limits<std::uint32_t>::max()) {
          remap[v] = static_cast<std::uint32_t>(pos.size() / 3);
          const MeshVertex& mv = pm.vertices[v];
          pos.insert(pos.end(), {mv.x, mv.y, mv.z});
          nrm.insert(nrm.end(), {mv.nx, mv.ny, mv.nz});
        }
        idx.push_back(remap[v]);
      }
    }
    if (idx.empty()) continue;
    std::vector<double> lo(3, std::numeric_limits<double>::infinity()),
        hi(3, -std::numeric_limits<double>::infinity());
    for (std::size_t k = 0; k < pos.size(); ++k) {
      lo[k % 3] = std::min(lo[k % 3], double(pos[k]));
      hi[k % 3] = std::max(hi[k % 3], double(pos[k]));
    }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    {
      tinygltf::Accessor a;
      a.bufferView = add_view(model, pos.data(), pos.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
      a.count = pos.size() / 3;
      a.type = TINYGLTF_TYPE_VEC3;
      a.minValues = lo;
      a.maxValues = hi;
      model.accessors.push_back(a);
      prim.attributes["POSITION"] = static_cast<int>(model.accessors.size() - 1);
    }
    if (options.normals) {
      tinygltf::Accessor a;
      a.bufferView = add_view(model, nrm.data(), nrm.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
      a.count = nrm.size() / 3;
      a.type = TINYGLTF_TYPE_VEC3;
      model.accessors.push_back(a);
      prim.attributes["NORMAL"] = static_cast<int>(model.accessors.size() - 1);
    }
    {
      tinygltf::Accessor a;
      a.bufferView =
          add_view(model, idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
      a.count = idx.size();
      a.type = TINYGLTF_TYPE_SCALAR;
      model.accessors.push_back(a);
      prim.indices = static_cast<int>(model.accessors.size() - 1);
    }
    tinygltf::Mesh mesh;
    mesh.name = fmt("patch_%u", p);
    mesh.primitives.push_back(prim);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = mesh.name;
    node.mesh = static_cast<int>(model.meshes.size() - 1);
    node.translation = {pm.origin_x, pm.origin_y, pm.origin_z};
    model.nodes.push_back(node);
    scene.nodes.push_back(static_cast<int>(model.nodes.size() - 1));
  }
  if (model.meshes.empty()) return Error{fmt("glTF export '%s': the mesh is empty", path.c_str())};
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  const std::string tmp = path + ".tmp";
  tinygltf::TinyGLTF writer;
  std::error_code ec;
  // tinygltf reports success for some failed writes: check that the file is there.
  if (!writer.WriteGltfSceneToFile(&model, tmp, true, true, false, true) ||
      std::filesystem::file_size(tmp, ec) == 0 || ec) {
    std::remove(tmp.c_str());
    return Error{fmt("glTF export '%s': cannot write '%s'", path.c_str(), tmp.c_str())};
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    return Error{
        fmt("glTF export '%s': cannot rename into place: %s", path.c_str(), ec.message().c_str())};
  }
  return {};
}

}  // namespace ridgeline::io
