// Vehicle models from glTF 2.0 through tinygltf: nodes flattened with their transforms.
#include "vehicle_model.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

namespace game {
namespace {

using ridgeline::Error;

glm::mat4 local_matrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    glm::mat4 m;
    for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = static_cast<float>(n.matrix[i]);
    return m;
  }
  glm::mat4 m(1.0f);
  if (n.translation.size() == 3)
    m = glm::translate(m, glm::vec3(n.translation[0], n.translation[1], n.translation[2]));
  if (n.rotation.size() == 4)
    m *= glm::mat4_cast(glm::quat(static_cast<float>(n.rotation[3]),
                                  static_cast<float>(n.rotation[0]),
                                  static_cast<float>(n.rotation[1]),
                                  static_cast<float>(n.rotation[2])));
  if (n.scale.size() == 3) m = glm::scale(m, glm::vec3(n.scale[0], n.scale[1], n.scale[2]));
  return m;
}

// Reads a float VEC3 accessor into `out`; empty string on success, else the problem.
std::string read_vec3(const tinygltf::Model& m, int index, std::vector<glm::vec3>& out) {
  if (index < 0 || index >= int(m.accessors.size())) return "accessor index out of range";
  const tinygltf::Accessor& a = m.accessors[index];
  if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.type != TINYGLTF_TYPE_VEC3)
    return "accessor " + std::to_string(index) + " is not float VEC3";
  if (a.bufferView < 0 || a.bufferView >= int(m.bufferViews.size())) return "no buffer view";
  const tinygltf::BufferView& bv = m.bufferViews[a.bufferView];
  const auto& data = m.buffers.at(bv.buffer).data;
  const std::size_t stride = bv.byteStride ? bv.byteStride : 12;
  const std::size_t start = bv.byteOffset + a.byteOffset;
  if (a.count > 0 && start + (a.count - 1) * stride + 12 > data.size())
    return "accessor " + std::to_string(index) + " runs past its buffer";
  out.resize(a.count);
  for (std::size_t i = 0; i < a.count; ++i) std::memcpy(&out[i], &data[start + i * stride], 12);
  return {};
}

std::string read_indices(const tinygltf::Model& m, int index, std::vector<std::uint32_t>& out) {
  if (index < 0 || index >= int(m.accessors.size())) return "index accessor out of range";
  const tinygltf::Accessor& a = m.accessors[index];
  if (a.type != TINYGLTF_TYPE_SCALAR || a.bufferView < 0 ||
      a.bufferView >= int(m.bufferViews.size()))
    return "bad index accessor";
  const tinygltf::BufferView& bv = m.bufferViews[a.bufferView];
  const auto& data = m.buffers.at(bv.buffer).data;
  std::size_t size = 0;
  switch (a.componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: size = 1; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: size = 2; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: size = 4; break;
    default: return "index component type " + std::to_string(a.componentType);
  }
  const std::size_t stride = bv.byteStride ? bv.byteStride : size;
  const std::size_t start = bv.byteOffset + a.byteOffset;
  if (a.count > 0 && start + (a.count - 1) * stride + size > data.size())
    return "index accessor runs past its buffer";
  out.resize(a.count);
  for (std::size_t i = 0; i < a.count; ++i) {
    const unsigned char* p = &data[start + i * stride];
    std::uint32_t v = 0;
    if (size == 1) v = p[0];
    else if (size == 2) { std::uint16_t s; std::memcpy(&s, p, 2); v = s; }
    else std::memcpy(&v, p, 4);
    out[i] = v;
  }
  return {};
}

// Appends mesh `mesh_index` transformed by `xf` to `out`.
std::string append_mesh(const tinygltf::Model& m, int mesh_index, const glm::mat4& xf,
                        ModelMesh& out) {
  if (mesh_index < 0 || mesh_index >= int(m.meshes.size())) return "mesh index out of range";
  const glm::mat3 nxf = glm::transpose(glm::inverse(glm::mat3(xf)));
  for (const tinygltf::Primitive& p : m.meshes[mesh_index].primitives) {
    if (p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != -1) return "a primitive is not triangles";
    std::vector<glm::vec3> pos, nrm;
    auto it = p.attributes.find("POSITION");
    if (it == p.attributes.end()) return "a primitive has no POSITION";
    if (std::string e = read_vec3(m, it->second, pos); !e.empty()) return e;
    it = p.attributes.find("NORMAL");
    if (it == p.attributes.end()) return "a primitive has no NORMAL";
    if (std::string e = read_vec3(m, it->second, nrm); !e.empty()) return e;
    if (nrm.size() != pos.size()) return "NORMAL and POSITION counts differ";
    std::vector<std::uint32_t> idx;
    if (p.indices >= 0) {
      if (std::string e = read_indices(m, p.indices, idx); !e.empty()) return e;
    } else {
      idx.resize(pos.size());
      for (std::uint32_t i = 0; i < idx.size(); ++i) idx[i] = i;
    }
    if (idx.size() % 3) return "index count not a multiple of 3";
    glm::vec3 colour(0.7f);
    if (p.material >= 0 && p.material < int(m.materials.size())) {
      const auto& f = m.materials[p.material].pbrMetallicRoughness.baseColorFactor;
      if (f.size() >= 3) colour = glm::vec3(f[0], f[1], f[2]);
    }
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (std::size_t i = 0; i < pos.size(); ++i) {
      const glm::vec3 q = glm::vec3(xf * glm::vec4(pos[i], 1.0f));
      glm::vec3 n = nxf * nrm[i];
      const float len = glm::length(n);
      n = len > 0 ? n / len : glm::vec3(0, 1, 0);
      out.vertices.push_back({q.x, q.y, q.z, n.x, n.y, n.z, colour.r, colour.g, colour.b});
    }
    for (std::uint32_t i : idx) {
      if (i >= pos.size()) return "index " + std::to_string(i) + " out of range";
      out.indices.push_back(base + i);
    }
  }
  return {};
}

}  // namespace

ridgeline::Result<VehicleModel> load_vehicle_model(const std::string& path) {
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  const bool binary = path.size() > 4 && path.compare(path.size() - 4, 4, ".glb") == 0;
  const bool ok = binary ? loader.LoadBinaryFromFile(&m, &err, &warn, path)
                         : loader.LoadASCIIFromFile(&m, &err, &warn, path);
  if (!ok) return Error{"vehicle model '" + path + "': " + (err.empty() ? "cannot load" : err)};
  VehicleModel vm;
  vm.name = path;
  static const char* const kWheels[4] = {"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"};
  bool found[4] = {};
  int wheel_mesh = -1;
  std::string problem;
  // Depth-first over the default scene (or every root when there is none).
  std::vector<std::pair<int, glm::mat4>> stack;
  const int scene = m.defaultScene >= 0 ? m.defaultScene : 0;
  if (scene < int(m.scenes.size()))
    for (int n : m.scenes[scene].nodes) stack.push_back({n, glm::mat4(1.0f)});
  int visited = 0;
  while (!stack.empty() && problem.empty()) {
    auto [ni, parent] = stack.back();
    stack.pop_back();
    if (ni < 0 || ni >= int(m.nodes.size()) || ++visited > 10000) {
      problem = "bad node index or a node cycle";
      break;
    }
    const tinygltf::Node& n = m.nodes[ni];
    const glm::mat4 xf = parent * local_matrix(n);
    int wheel = -1;
    for (int w = 0; w < 4; ++w)
      if (n.name == kWheels[w]) wheel = w;
    if (wheel >= 0) {
      found[wheel] = true;
      vm.wheel_centres[wheel] = glm::vec3(xf[3]);
      if (n.mesh >= 0) wheel_mesh = n.mesh;
    } else if (n.mesh >= 0) {
      problem = append_mesh(m, n.mesh, xf, vm.body);
    }
    for (int c : n.children) stack.push_back({c, xf});
  }
  if (!problem.empty()) return Error{"vehicle model '" + path + "': " + problem};
  for (int w = 0; w < 4; ++w)
    if (!found[w])
      return Error{"vehicle model '" + path + "': no node named '" + kWheels[w] + "'"};
  if (wheel_mesh < 0) return Error{"vehicle model '" + path + "': the wheel nodes have no mesh"};
  if (std::string e = append_mesh(m, wheel_mesh, glm::mat4(1.0f), vm.wheel); !e.empty())
    return Error{"vehicle model '" + path + "': wheel mesh: " + e};
  if (vm.body.vertices.empty()) return Error{"vehicle model '" + path + "': no body mesh"};
  float r = 0;
  for (const ModelVertex& v : vm.wheel.vertices) r = std::max(r, std::hypot(v.py, v.pz));
  if (!(r > 0.05f && r < 5.0f))
    return Error{"vehicle model '" + path + "': wheel radius " + std::to_string(r) +
                 " m outside 0.05 .. 5"};
  vm.wheel_radius = r;
  vm.body_min = glm::vec3(1e9f);
  vm.body_max = glm::vec3(-1e9f);
  for (const ModelVertex& v : vm.body.vertices) {
    vm.body_min = glm::min(vm.body_min, glm::vec3(v.px, v.py, v.pz));
    vm.body_max = glm::max(vm.body_max, glm::vec3(v.px, v.py, v.pz));
  }
  return vm;
}

}  // namespace game
