// Meshes for surface noise: Assimp loading, vertex colours, seamless UV baking. See mesh.h.
#include "analysis/mesh.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace stex {

namespace {

[[noreturn]] void bad_input(const std::string& message) { throw Error(ErrorKind::Input, message); }

constexpr std::uint64_t k_max_mesh_file_bytes = std::uint64_t(1) << 31;

std::vector<char> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad_input("cannot open mesh file '" + path + "'");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size <= 0) bad_input("mesh file '" + path + "' is empty or unreadable");
  if (std::uint64_t(size) > k_max_mesh_file_bytes)
    throw Error(ErrorKind::Limit, "mesh file '" + path + "' is larger than 2 GiB");
  in.seekg(0);
  std::vector<char> data(static_cast<std::size_t>(size));
  in.read(data.data(), size);
  if (!in) bad_input("cannot read mesh file '" + path + "'");
  return data;
}

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Smooth normals where the file has none: area-weighted face normals summed over every vertex at the same
// exact position (so vertices split at UV seams get bit-identical normals), normalised.
void generate_normals(Mesh& m) {
  std::map<std::array<double, 3>, std::size_t> group_of;
  std::vector<std::size_t> group(m.vertex_count());
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const std::array<double, 3> p{m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
    group[v] = group_of.emplace(p, group_of.size()).first->second;
  }
  std::vector<double> acc(3 * group_of.size(), 0.0);
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const double* a = &m.positions[3 * m.triangles[3 * t]];
    const double* b = &m.positions[3 * m.triangles[3 * t + 1]];
    const double* c = &m.positions[3 * m.triangles[3 * t + 2]];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    for (int k = 0; k < 3; ++k) {
      const std::size_t g = group[m.triangles[3 * t + k]];
      for (int i = 0; i < 3; ++i) acc[3 * g + i] += n[i];
    }
  }
  m.normals.assign(3 * m.vertex_count(), 0.0);
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const double* n = &acc[3 * group[v]];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int i = 0; i < 3; ++i) m.normals[3 * v + i] = len > 0.0 ? n[i] / len : (i == 2 ? 1.0 : 0.0);
  }
}

// A PLY header's element counts against the file's size, before Assimp allocates for them (it reserves
// memory for every declared element: a 100-byte file declaring 10^9 vertices took it 50 s and gigabytes).
// Every element takes at least one byte in any PLY encoding.
void check_ply_header(const std::vector<char>& data, const std::string& path) {
  const std::size_t probe = std::min<std::size_t>(data.size(), 1 << 16);
  const std::string head(data.data(), probe);
  const auto end = head.find("end_header");
  if (end == std::string::npos) bad_input("mesh file '" + path + "': PLY header without end_header");
  std::istringstream in(head.substr(0, end));
  std::string line;
  std::uint64_t total = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string word, name;
    long double count = -1;
    if (!(ls >> word) || word != "element") continue;
    if (!(ls >> name >> count) || count < 0) bad_input("mesh file '" + path + "': bad PLY element line '" + line + "'");
    if (count > (long double)data.size() || (total += std::uint64_t(count)) > data.size())
      bad_input("mesh file '" + path + "' is truncated: its PLY header declares more elements than the file's " +
                std::to_string(data.size()) + " bytes can hold");
    if (name == "vertex" && std::uint64_t(count) > k_max_mesh_vertices)
      throw Error(ErrorKind::Limit, "mesh file '" + path + "' declares more than 2^26 vertices");
  }
}

}  // namespace

void validate_mesh(const Mesh& m) {
  if (m.positions.size() % 3 != 0 || m.triangles.size() % 3 != 0) bad_input("mesh arrays have bad sizes");
  const std::size_t nv = m.vertex_count();
  if (nv == 0 || m.triangle_count() == 0) bad_input("mesh has no triangles");
  if (nv > k_max_mesh_vertices || m.triangle_count() > k_max_mesh_triangles)
    throw Error(ErrorKind::Limit, "mesh has " + std::to_string(nv) + " vertices and " +
                                      std::to_string(m.triangle_count()) + " triangles (limits 2^26 and 2^27)");
  if (m.normals.size() != 3 * nv) bad_input("mesh normals: expected 3 per vertex");
  if (!m.uvs.empty() && m.uvs.size() != 2 * nv) bad_input("mesh UVs: expected 2 per vertex");
  for (double v : m.positions)
    if (!std::isfinite(v)) bad_input("mesh has a non-finite vertex position");
  for (double v : m.normals)
    if (!std::isfinite(v)) bad_input("mesh has a non-finite normal");
  for (double v : m.uvs)
    if (!std::isfinite(v)) bad_input("mesh has a non-finite UV");
  for (std::uint32_t i : m.triangles)
    if (i >= nv) bad_input("mesh triangle refers to vertex " + std::to_string(i) + " of " + std::to_string(nv));
}

Mesh load_mesh(const std::string& path) {
  const std::vector<char> data = read_file(path);
  // The format is chosen by content: a PLY header, or a text file named .obj. Anything else is refused
  // before Assimp sees it (it would try every importer it has).
  std::string hint;
  if (data.size() >= 4 && std::memcmp(data.data(), "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r')) {
    hint = "ply";
    check_ply_header(data, path);
  } else if (lower_extension(path) == "obj") {
    const std::size_t probe = std::min<std::size_t>(data.size(), 65536);
    if (std::find(data.begin(), data.begin() + std::ptrdiff_t(probe), '\0') != data.begin() + std::ptrdiff_t(probe))
      bad_input("mesh file '" + path + "' is named .obj but is not a text file");
    hint = "obj";
  } else {
    bad_input("mesh file '" + path + "' is neither PLY (by its header) nor OBJ (a text file named .obj)");
  }
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                         aiProcess_SortByPType;
  const aiScene* scene = importer.ReadFileFromMemory(data.data(), data.size(), flags, hint.c_str());
  if (!scene || !scene->mRootNode || scene->mNumMeshes == 0)
    bad_input("cannot read mesh file '" + path + "': " + importer.GetErrorString());
  Mesh m;
  bool all_normals = true, all_uvs = true;
  for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
    const aiMesh* am = scene->mMeshes[k];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    all_normals = all_normals && am->HasNormals();
    all_uvs = all_uvs && am->HasTextureCoords(0);
  }
  for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
    const aiMesh* am = scene->mMeshes[k];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const std::size_t base = m.vertex_count();
    if (base + am->mNumVertices > k_max_mesh_vertices)
      throw Error(ErrorKind::Limit, "mesh '" + path + "' has more than 2^26 vertices");
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      m.positions.insert(m.positions.end(), {am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z});
      if (all_normals) {
        const aiVector3D& n = am->mNormals[v];
        const double len = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
        if (!(len > 0.0) || !std::isfinite(len)) {
          all_normals = false;  // a zero normal: regenerate them all
        } else {
          m.normals.insert(m.normals.end(), {n.x / len, n.y / len, n.z / len});
        }
      }
      if (all_uvs) m.uvs.insert(m.uvs.end(), {am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y});
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int i = 0; i < 3; ++i) m.triangles.push_back(std::uint32_t(base + face.mIndices[i]));
    }
  }
  if (!all_uvs) m.uvs.clear();
  if (!all_normals || m.normals.size() != m.positions.size()) {
    if (m.triangles.empty()) bad_input("mesh file '" + path + "' has no triangles");
    generate_normals(m);
  }
  validate_mesh(m);
  return m;
}

std::vector<float> surface_vertex_values(SurfaceRenderer& renderer, const SurfaceParams& params,
                                         const Mesh& mesh) {
  validate_mesh(mesh);
  validate_surface_params(params);
  const std::size_t n = mesh.vertex_count();
  std::vector<float> pos(3 * n), frames(9 * n);
  for (std::size_t v = 0; v < n; ++v) {
    validate_surface_position(params, &mesh.positions[3 * v], v);
    for (int i = 0; i < 3; ++i) pos[3 * v + i] = float(mesh.positions[3 * v + i]);
    const auto f = surface_frame(&mesh.normals[3 * v], nullptr, v);
    std::copy(f.begin(), f.end(), frames.begin() + std::ptrdiff_t(9 * v));
  }
  std::vector<float> out(n * std::size_t(renderer.channels()));
  renderer.eval(params, n, pos.data(), frames.data(), out.data());
  return out;
}

void write_ply_with_colours(const std::string& path, const Mesh& mesh, const std::vector<float>& values,
                            int channels, bool encode_srgb) {
  const std::size_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  if (values.size() != nv * std::size_t(channels)) throw Error(ErrorKind::Internal, "vertex values size mismatch");
  std::ostringstream head;
  head << "ply\nformat binary_little_endian 1.0\ncomment stex surface noise (S1 6)\nelement vertex " << nv
       << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
          "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face "
       << nt << "\nproperty list uchar uint vertex_indices\nend_header\n";
  std::string out = head.str();
  out.reserve(out.size() + nv * 27 + nt * 13);
  auto put = [&out](const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); };
  for (std::size_t v = 0; v < nv; ++v) {
    for (int i = 0; i < 3; ++i) {
      const float f = float(mesh.positions[3 * v + i]);
      put(&f, 4);
    }
    for (int i = 0; i < 3; ++i) {
      const float f = float(mesh.normals[3 * v + i]);
      put(&f, 4);
    }
    for (int c = 0; c < 3; ++c) {
      float x = values[v * std::size_t(channels) + std::size_t(std::min(c, channels - 1))];
      if (encode_srgb) x = linear_to_srgb(x);
      x = std::isnan(x) ? 0.0f : std::min(1.0f, std::max(0.0f, x));
      const std::uint8_t b = std::uint8_t(std::lround(x * 255.0f));
      put(&b, 1);
    }
  }
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint8_t three = 3;
    put(&three, 1);
    put(&mesh.triangles[3 * t], 12);
  }
  write_file_atomic(path, out.data(), out.size());
}

BakeResult bake_surface_noise(SurfaceRenderer& renderer, const SurfaceParams& params, const TextonModel& model,
                              const Mesh& mesh, const BakeOptions& o) {
  validate_mesh(mesh);
  validate_surface_params(params);
  if (mesh.uvs.empty()) bad_input("the mesh has no UVs: cannot bake into a texture (write vertex colours instead)");
  if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384 ||
      std::uint64_t(o.width) * std::uint64_t(o.height) > (std::uint64_t(1) << 26))
    throw Error(ErrorKind::Usage, "--bake-size must be between 1x1 and 16384x16384 with at most 2^26 texels, got " +
                                      std::to_string(o.width) + "x" + std::to_string(o.height));
  if (o.gutter < 0 || o.gutter > 64)
    throw Error(ErrorKind::Usage, "--gutter must be in [0, 64] texels, got " + std::to_string(o.gutter));
  const int W = o.width, H = o.height;
  const std::size_t texels = std::size_t(W) * std::size_t(H);
  std::vector<float> best(texels, std::numeric_limits<float>::infinity());
  std::vector<std::uint32_t> tri_of(texels, 0);
  std::vector<float> bary(2 * texels, 0.0f);  // lambda1, lambda2 (lambda0 = 1 - both)

  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    double ax[3], ay[3];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[3 * t + k];
      ax[k] = mesh.uvs[2 * v] * W;
      ay[k] = (1.0 - mesh.uvs[2 * v + 1]) * H;
    }
    const double e1x = ax[1] - ax[0], e1y = ay[1] - ay[0], e2x = ax[2] - ax[0], e2y = ay[2] - ay[0];
    const double det = e1x * e2y - e2x * e1y;
    if (!(std::fabs(det) > 1e-12)) continue;  // degenerate in UV space: covers no texel
    const double g = double(o.gutter);
    const int i0 = std::max(0, int(std::floor(std::min({ax[0], ax[1], ax[2]}) - g - 0.5)));
    const int i1 = std::min(W - 1, int(std::ceil(std::max({ax[0], ax[1], ax[2]}) + g - 0.5)));
    const int j0 = std::max(0, int(std::floor(std::min({ay[0], ay[1], ay[2]}) - g - 0.5)));
    const int j1 = std::min(H - 1, int(std::ceil(std::max({ay[0], ay[1], ay[2]}) + g - 0.5)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double px = i + 0.5 - ax[0], py = j + 0.5 - ay[0];
        const double l1 = (px * e2y - e2x * py) / det, l2 = (e1x * py - px * e1y) / det, l0 = 1.0 - l1 - l2;
        double dist = 0.0;
        if (l0 < 0.0 || l1 < 0.0 || l2 < 0.0) {
          // Distance from the texel centre to the triangle: the nearest of its three edges.
          dist = std::numeric_limits<double>::infinity();
          for (int k = 0; k < 3; ++k) {
            const double sx = ax[k], sy = ay[k], dx = ax[(k + 1) % 3] - sx, dy = ay[(k + 1) % 3] - sy;
            const double qx = i + 0.5 - sx, qy = j + 0.5 - sy;
            const double len2 = dx * dx + dy * dy;
            const double u = len2 > 0.0 ? std::clamp((qx * dx + qy * dy) / len2, 0.0, 1.0) : 0.0;
            dist = std::min(dist, std::hypot(qx - u * dx, qy - u * dy));
          }
          if (dist > g) continue;
        }
        const std::size_t at = std::size_t(j) * W + i;
        if (float(dist) < best[at]) {  // strict: ties keep the lower triangle index (deterministic)
          best[at] = float(dist);
          tri_of[at] = std::uint32_t(t);
          bary[2 * at] = float(l1);
          bary[2 * at + 1] = float(l2);
        }
      }
  }

  BakeResult res;
  const int nc = model.channels;
  res.image.width = W;
  res.image.height = H;
  res.image.channels = nc;
  res.image.pixels.resize(texels * std::size_t(nc));
  res.covered.assign(texels, 0);
  std::vector<std::size_t> at_list;
  std::vector<float> pos, frames;
  for (std::size_t at = 0; at < texels; ++at) {
    if (!std::isfinite(best[at])) {
      for (int c = 0; c < nc; ++c) res.image.pixels[at * nc + c] = model.mean[c];
      continue;
    }
    res.covered[at] = best[at] == 0.0f ? 1 : 2;
    const std::uint32_t* tv = &mesh.triangles[3 * std::size_t(tri_of[at])];
    const double l1 = bary[2 * at], l2 = bary[2 * at + 1], l0 = 1.0 - l1 - l2;
    const double lw[3] = {l0, l1, l2};
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) {
        p[i] += lw[k] * mesh.positions[3 * tv[k] + i];
        n[i] += lw[k] * mesh.normals[3 * tv[k] + i];
      }
    if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 1e-20)) n[0] = 1.0;  // opposite normals cancel: any frame
    validate_surface_position(params, p, tv[0]);
    const auto f = surface_frame(n, nullptr, tv[0]);
    at_list.push_back(at);
    for (int i = 0; i < 3; ++i) pos.push_back(float(p[i]));
    frames.insert(frames.end(), f.begin(), f.end());
  }
  std::vector<float> vals(at_list.size() * std::size_t(nc));
  renderer.eval(params, at_list.size(), pos.data(), frames.data(), vals.data());
  for (std::size_t k = 0; k < at_list.size(); ++k)
    for (int c = 0; c < nc; ++c) res.image.pixels[at_list[k] * nc + c] = vals[k * nc + c];
  return res;
}

void sample_bilinear(const Image& img, double u, double v, float* out) {
  const double x = u * img.width - 0.5, y = (1.0 - v) * img.height - 0.5;
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double fx = x - fx0, fy = y - fy0;
  auto clampi = [](long v, int n) { return int(std::min<long>(std::max<long>(v, 0), n - 1)); };
  const int x0 = clampi(long(fx0), img.width), x1 = clampi(long(fx0) + 1, img.width);
  const int y0 = clampi(long(fy0), img.height), y1 = clampi(long(fy0) + 1, img.height);
  for (int c = 0; c < img.channels; ++c)
    out[c] = float((1 - fx) * (1 - fy) * img.at(x0, y0, c) + fx * (1 - fy) * img.at(x1, y0, c) +
                   (1 - fx) * fy * img.at(x0, y1, c) + fx * fy * img.at(x1, y1, c));
}

Image render_mesh_preview(SurfaceRenderer& renderer, const SurfaceParams& params, const Mesh& mesh,
                          const PreviewOptions& o) {
  validate_mesh(mesh);
  validate_surface_params(params);
  if (o.width < 1 || o.height < 1 || o.width > 8192 || o.height > 8192)
    throw Error(ErrorKind::Usage, "--preview-size must be between 1x1 and 8192x8192");
  auto normalised = [](std::array<double, 3> v, const char* what) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 0.0) || !std::isfinite(l)) throw Error(ErrorKind::Usage, std::string(what) + " must be a non-zero vector");
    for (double& x : v) x /= l;
    return v;
  };
  const std::array<double, 3> w = normalised(o.view, "--view"), light = normalised(o.light, "light");
  // Camera basis: w towards the camera, e1 horizontal (world up = +Y unless w is vertical), e2 up.
  std::array<double, 3> up{0.0, 1.0, 0.0};
  if (std::fabs(w[1]) > 0.999) up = {0.0, 0.0, -1.0};
  std::array<double, 3> e1{up[1] * w[2] - up[2] * w[1], up[2] * w[0] - up[0] * w[2], up[0] * w[1] - up[1] * w[0]};
  e1 = normalised(e1, "--view");
  const std::array<double, 3> e2{w[1] * e1[2] - w[2] * e1[1], w[2] * e1[0] - w[0] * e1[2], w[0] * e1[1] - w[1] * e1[0]};
  const std::size_t nv = mesh.vertex_count();
  std::vector<double> sx(nv), sy(nv), sz(nv);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (std::size_t v = 0; v < nv; ++v) {
    const double* p = &mesh.positions[3 * v];
    sx[v] = p[0] * e1[0] + p[1] * e1[1] + p[2] * e1[2];
    sy[v] = p[0] * e2[0] + p[1] * e2[1] + p[2] * e2[2];
    sz[v] = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
    x0 = std::min(x0, sx[v]);
    x1 = std::max(x1, sx[v]);
    y0 = std::min(y0, sy[v]);
    y1 = std::max(y1, sy[v]);
  }
  const double extent = std::max(x1 - x0, y1 - y0);
  const double pix = (extent > 0.0 ? extent : 1.0) * 1.05 / std::min(o.width, o.height);  // world per pixel
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const std::size_t npx = std::size_t(o.width) * std::size_t(o.height);
  std::vector<double> depth(npx, -1e300);
  std::vector<std::uint32_t> tri(npx, 0);
  std::vector<float> bary(2 * npx, 0.0f);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    double px[3], py[3];
    const std::uint32_t* tv = &mesh.triangles[3 * t];
    for (int k = 0; k < 3; ++k) {
      px[k] = (sx[tv[k]] - cx) / pix + 0.5 * o.width;
      py[k] = (cy - sy[tv[k]]) / pix + 0.5 * o.height;
    }
    const double e1x = px[1] - px[0], e1y = py[1] - py[0], e2x = px[2] - px[0], e2y = py[2] - py[0];
    const double det = e1x * e2y - e2x * e1y;
    if (!(std::fabs(det) > 1e-12)) continue;
    const int i0 = std::max(0, int(std::floor(std::min({px[0], px[1], px[2]}))));
    const int i1 = std::min(o.width - 1, int(std::ceil(std::max({px[0], px[1], px[2]}))));
    const int j0 = std::max(0, int(std::floor(std::min({py[0], py[1], py[2]}))));
    const int j1 = std::min(o.height - 1, int(std::ceil(std::max({py[0], py[1], py[2]}))));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double qx = i + 0.5 - px[0], qy = j + 0.5 - py[0];
        const double l1 = (qx * e2y - e2x * qy) / det, l2 = (e1x * qy - qx * e1y) / det, l0 = 1.0 - l1 - l2;
        if (l0 < 0.0 || l1 < 0.0 || l2 < 0.0) continue;
        const double z = l0 * sz[tv[0]] + l1 * sz[tv[1]] + l2 * sz[tv[2]];
        const std::size_t at = std::size_t(j) * o.width + i;
        if (z > depth[at]) {
          depth[at] = z;
          tri[at] = std::uint32_t(t);
          bary[2 * at] = float(l1);
          bary[2 * at + 1] = float(l2);
        }
      }
  }
  std::vector<std::size_t> at_list;
  std::vector<float> pos, frames, shade;
  for (std::size_t at = 0; at < npx; ++at) {
    if (depth[at] == -1e300) continue;
    const std::uint32_t* tv = &mesh.triangles[3 * std::size_t(tri[at])];
    const double l1 = bary[2 * at], l2 = bary[2 * at + 1], lw[3] = {1.0 - l1 - l2, l1, l2};
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) {
        p[i] += lw[k] * mesh.positions[3 * tv[k] + i];
        n[i] += lw[k] * mesh.normals[3 * tv[k] + i];
      }
    if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 1e-20)) n[0] = 1.0;
    validate_surface_position(params, p, tv[0]);
    const auto f = surface_frame(n, nullptr, tv[0]);
    double ndl = f[6] * light[0] + f[7] * light[1] + f[8] * light[2];
    if (f[6] * w[0] + f[7] * w[1] + f[8] * w[2] < 0.0) ndl = -ndl;  // back faces lit like front faces
    at_list.push_back(at);
    shade.push_back(float(0.35 + 0.65 * std::max(0.0, ndl)));
    for (int i = 0; i < 3; ++i) pos.push_back(float(p[i]));
    frames.insert(frames.end(), f.begin(), f.end());
  }
  const int nc = renderer.channels();
  std::vector<float> vals(at_list.size() * std::size_t(nc));
  renderer.eval(params, at_list.size(), pos.data(), frames.data(), vals.data());
  Image img;
  img.width = o.width;
  img.height = o.height;
  img.channels = 3;
  img.pixels.resize(npx * 3);
  for (std::size_t at = 0; at < npx; ++at)
    for (int c = 0; c < 3; ++c) img.pixels[at * 3 + c] = o.background[c];
  for (std::size_t k = 0; k < at_list.size(); ++k)
    for (int c = 0; c < 3; ++c) img.pixels[at_list[k] * 3 + c] = vals[k * nc + std::min(c, nc - 1)] * shade[k];
  return img;
}

}  // namespace stex
