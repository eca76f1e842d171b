// Writes the sample game's vehicle models (glTF 2.0 binary) with tinygltf:
//   make_vehicles OUT_DIR  ->  OUT_DIR/truck.glb, OUT_DIR/buggy.glb
// Models are built from boxes and cylinders. Conventions the game relies on (docs/game.md):
// metres, +y up, +z forward, +x to the vehicle's left; a node named "body" with the chassis; one
// mesh named "wheel" (a cylinder around the x axis, its radius is the wheel radius) used by four
// nodes named wheel_fl, wheel_fr, wheel_rl, wheel_rr whose translations are the wheel centres at
// rest. Colours are material base colour factors (no textures).
#include <tiny_gltf.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct Prim {
  std::vector<float> pos, nrm;
  std::vector<std::uint32_t> idx;
  int material = 0;
};

void quad(Prim& p, const float* a, const float* b, const float* c, const float* d, const float* n) {
  const auto base = static_cast<std::uint32_t>(p.pos.size() / 3);
  for (const float* v : {a, b, c, d}) {
    p.pos.insert(p.pos.end(), v, v + 3);
    p.nrm.insert(p.nrm.end(), n, n + 3);
  }
  for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) p.idx.push_back(base + i);
}

// Axis-aligned box from (x0,y0,z0) to (x1,y1,z1), optionally with the top face's front edge
// lowered by `slope` metres (a wedge nose).
void box(Prim& p, float x0, float y0, float z0, float x1, float y1, float z1, float slope = 0) {
  const float yf = y1 - slope;  // top height at the front (z1)
  const float v[8][3] = {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1},
                         {x0, y1, z0}, {x1, y1, z0}, {x1, yf, z1}, {x0, yf, z1}};
  const float up_len = std::sqrt(slope * slope + (z1 - z0) * (z1 - z0));
  const float top[3] = {0, (z1 - z0) / up_len, slope / up_len};
  const float down[3] = {0, -1, 0}, px[3] = {1, 0, 0}, nx[3] = {-1, 0, 0}, pz[3] = {0, 0, 1},
              nz[3] = {0, 0, -1};
  quad(p, v[0], v[1], v[2], v[3], down);
  quad(p, v[4], v[7], v[6], v[5], top);
  quad(p, v[1], v[5], v[6], v[2], px);
  quad(p, v[0], v[3], v[7], v[4], nx);
  quad(p, v[3], v[2], v[6], v[7], pz);
  quad(p, v[0], v[4], v[5], v[1], nz);
}

// Cylinder around the x axis, centred at the origin.
void cylinder(Prim& p, float radius, float width, int segments) {
  const float h = width / 2;
  for (int s = 0; s < segments; ++s) {
    const float a0 = 2 * float(M_PI) * s / segments, a1 = 2 * float(M_PI) * (s + 1) / segments;
    const float y0 = radius * std::cos(a0), z0 = radius * std::sin(a0);
    const float y1 = radius * std::cos(a1), z1 = radius * std::sin(a1);
    const float am = (a0 + a1) / 2;
    const float n[3] = {0, std::cos(am), std::sin(am)};
    const float a[3] = {-h, y0, z0}, b[3] = {h, y0, z0}, c[3] = {h, y1, z1}, d[3] = {-h, y1, z1};
    quad(p, a, d, c, b, n);
    const float px[3] = {1, 0, 0}, nx[3] = {-1, 0, 0};
    const float cp[3] = {h, 0, 0}, cn[3] = {-h, 0, 0};
    quad(p, cp, b, c, cp, px);
    quad(p, cn, d, a, cn, nx);
  }
}

int add_view(tinygltf::Model& m, const void* data, std::size_t bytes, int target) {
  auto& buf = m.buffers[0].data;
  while (buf.size() % 4) buf.push_back(0);
  tinygltf::BufferView bv;
  bv.buffer = 0;
  bv.byteOffset = buf.size();
  bv.byteLength = bytes;
  bv.target = target;
  const auto* b = static_cast<const unsigned char*>(data);
  buf.insert(buf.end(), b, b + bytes);
  m.bufferViews.push_back(bv);
  return static_cast<int>(m.bufferViews.size() - 1);
}

int add_mesh(tinygltf::Model& m, const std::string& name, const std::vector<Prim>& prims) {
  tinygltf::Mesh mesh;
  mesh.name = name;
  for (const Prim& p : prims) {
    tinygltf::Primitive prim;
    tinygltf::Accessor pa;
    pa.bufferView = add_view(m, p.pos.data(), p.pos.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
    pa.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    pa.type = TINYGLTF_TYPE_VEC3;
    pa.count = p.pos.size() / 3;
    pa.minValues = {1e9, 1e9, 1e9};
    pa.maxValues = {-1e9, -1e9, -1e9};
    for (std::size_t i = 0; i < p.pos.size(); ++i) {
      pa.minValues[i % 3] = std::min(pa.minValues[i % 3], double(p.pos[i]));
      pa.maxValues[i % 3] = std::max(pa.maxValues[i % 3], double(p.pos[i]));
    }
    m.accessors.push_back(pa);
    prim.attributes["POSITION"] = static_cast<int>(m.accessors.size() - 1);
    tinygltf::Accessor na;
    na.bufferView = add_view(m, p.nrm.data(), p.nrm.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
    na.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    na.type = TINYGLTF_TYPE_VEC3;
    na.count = p.nrm.size() / 3;
    m.accessors.push_back(na);
    prim.attributes["NORMAL"] = static_cast<int>(m.accessors.size() - 1);
    tinygltf::Accessor ia;
    ia.bufferView =
        add_view(m, p.idx.data(), p.idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    ia.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    ia.type = TINYGLTF_TYPE_SCALAR;
    ia.count = p.idx.size();
    m.accessors.push_back(ia);
    prim.indices = static_cast<int>(m.accessors.size() - 1);
    prim.material = p.material;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    mesh.primitives.push_back(prim);
  }
  m.meshes.push_back(mesh);
  return static_cast<int>(m.meshes.size() - 1);
}

int add_material(tinygltf::Model& m, const std::string& name, float r, float g, float b,
                 float metal, float rough) {
  tinygltf::Material mat;
  mat.name = name;
  mat.pbrMetallicRoughness.baseColorFactor = {r, g, b, 1.0};
  mat.pbrMetallicRoughness.metallicFactor = metal;
  mat.pbrMetallicRoughness.roughnessFactor = rough;
  m.materials.push_back(mat);
  return static_cast<int>(m.materials.size() - 1);
}

struct Spec {
  std::string name;
  float wheel_radius, wheel_width, track, front_z, rear_z, wheel_y;
};

bool write(const std::string& path, tinygltf::Model& m, const Spec& s, int body_mesh) {
  Prim wheel;
  wheel.material = static_cast<int>(m.materials.size());
  add_material(m, "tyre", 0.08f, 0.08f, 0.09f, 0.0f, 0.9f);
  cylinder(wheel, s.wheel_radius, s.wheel_width, 18);
  const int wheel_mesh = add_mesh(m, "wheel", {wheel});
  tinygltf::Scene scene;
  tinygltf::Node body;
  body.name = "body";
  body.mesh = body_mesh;
  m.nodes.push_back(body);
  scene.nodes.push_back(0);
  const char* names[4] = {"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"};
  for (int w = 0; w < 4; ++w) {
    tinygltf::Node n;
    n.name = names[w];
    n.mesh = wheel_mesh;
    const double x = (w % 2 == 0) ? s.track / 2 : -s.track / 2;
    const double z = w < 2 ? s.front_z : s.rear_z;
    n.translation = {x, s.wheel_y, z};
    m.nodes.push_back(n);
    scene.nodes.push_back(static_cast<int>(m.nodes.size() - 1));
  }
  m.scenes.push_back(scene);
  m.defaultScene = 0;
  m.asset.version = "2.0";
  m.asset.generator = "ridgeline sample_game/tools/make_vehicles";
  m.buffers[0].name = s.name;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&m, path, true, true, false, true)) {
    std::fprintf(stderr, "make_vehicles: cannot write '%s'\n", path.c_str());
    return false;
  }
  std::printf("%s\n", path.c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_vehicles OUT_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  bool ok = true;
  {  // truck: a long flatbed with a cab, orange.
    tinygltf::Model m;
    m.buffers.resize(1);
    Prim paint, dark, glass;
    paint.material = add_material(m, "paint", 0.95f, 0.45f, 0.08f, 0.2f, 0.5f);
    dark.material = add_material(m, "chassis", 0.18f, 0.18f, 0.2f, 0.5f, 0.7f);
    glass.material = add_material(m, "glass", 0.25f, 0.4f, 0.55f, 0.0f, 0.1f);
    box(dark, -1.1f, 0.45f, -3.0f, 1.1f, 0.85f, 3.0f);          // frame
    box(paint, -1.2f, 0.85f, 0.9f, 1.2f, 2.7f, 2.9f, 0.4f);     // cab
    box(glass, -1.05f, 1.9f, 2.55f, 1.05f, 2.45f, 2.95f, 0.3f); // windscreen
    box(paint, -1.25f, 0.85f, -3.0f, 1.25f, 1.5f, 0.7f);        // bed
    box(dark, -1.15f, 1.5f, -2.9f, 1.15f, 1.6f, 0.6f);          // cargo cover
    const int body = add_mesh(m, "truck_body", {paint, dark, glass});
    ok &= write(dir + "/truck.glb", m, {"truck", 0.55f, 0.4f, 2.2f, 2.0f, -2.0f, 0.55f}, body);
  }
  {  // buggy: a low wedge with a roll cage, green.
    tinygltf::Model m;
    m.buffers.resize(1);
    Prim paint, dark;
    paint.material = add_material(m, "paint", 0.2f, 0.75f, 0.3f, 0.1f, 0.4f);
    dark.material = add_material(m, "cage", 0.12f, 0.12f, 0.12f, 0.8f, 0.5f);
    box(paint, -0.8f, 0.35f, -1.7f, 0.8f, 0.95f, 1.8f, 0.45f);  // wedge tub
    box(dark, -0.75f, 0.95f, -0.9f, -0.65f, 1.75f, -0.8f);      // cage posts
    box(dark, 0.65f, 0.95f, -0.9f, 0.75f, 1.75f, -0.8f);
    box(dark, -0.75f, 0.95f, 0.3f, -0.65f, 1.75f, 0.4f);
    box(dark, 0.65f, 0.95f, 0.3f, 0.75f, 1.75f, 0.4f);
    box(dark, -0.75f, 1.7f, -0.9f, 0.75f, 1.8f, 0.4f);          // roof bar frame
    box(dark, -0.6f, 0.95f, -1.6f, 0.6f, 1.25f, -1.1f);         // engine
    const int body = add_mesh(m, "buggy_body", {paint, dark});
    ok &= write(dir + "/buggy.glb", m, {"buggy", 0.45f, 0.35f, 1.8f, 1.25f, -1.25f, 0.45f}, body);
  }
  return ok ? 0 : 1;
}
