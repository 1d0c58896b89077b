// A glTF 2.0 file assembled in a test: JSON with one buffer as a base64 data URI and a buffer view
// per accessor, so that each test states its nodes, meshes, skins and animations in a few lines.
#pragma once
#include <string>
#include <vector>

#include "test_util.hpp"

namespace isochor::test {

struct GltfBuilder {
  std::string bin;
  std::vector<std::string> views, accessors;
  std::string nodes, meshes, skins, animations, scenes = "[{\"nodes\":[0]}]";

  template <class T>
  int add(const std::vector<T>& v, const std::string& type, int component_type, const std::string& extra = "") {
    while (bin.size() % 4) bin.push_back('\0');
    const std::size_t offset = bin.size(), bytes = v.size() * sizeof(T);
    bin.append(reinterpret_cast<const char*>(v.data()), bytes);
    const int per = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 16;
    views.push_back("{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) +
                    ",\"byteLength\":" + std::to_string(bytes) + "}");
    accessors.push_back("{\"bufferView\":" + std::to_string(views.size() - 1) +
                        ",\"componentType\":" + std::to_string(component_type) +
                        ",\"count\":" + std::to_string(v.size() / per) + ",\"type\":\"" + type + "\"" + extra + "}");
    return static_cast<int>(accessors.size() - 1);
  }
  int floats(const std::vector<float>& v, const std::string& type, const std::string& extra = "") {
    return add(v, type, 5126, extra);
  }

  // meshes: one indexed triangle primitive with a skin's JOINTS_0 and WEIGHTS_0.
  void skinned_mesh(int pos, int joints, int weights, int indices) {
    meshes = "[{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
             ",\"JOINTS_0\":" + std::to_string(joints) + ",\"WEIGHTS_0\":" + std::to_string(weights) +
             "},\"indices\":" + std::to_string(indices) + "}]}]";
  }
  // animations: one clip of one sampler driving one node's path (rotation, translation, scale).
  void one_channel_clip(const std::string& name, int times, int values, int node, const std::string& path) {
    animations = "[{\"name\":\"" + name + "\",\"samplers\":[{\"input\":" + std::to_string(times) +
                 ",\"output\":" + std::to_string(values) +
                 "}],\"channels\":[{\"sampler\":0,\"target\":{\"node\":" + std::to_string(node) + ",\"path\":\"" +
                 path + "\"}}]}]";
  }

  static std::string base64(const std::string& s) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < s.size(); i += 3) {
      unsigned n = static_cast<unsigned char>(s[i]) << 16;
      if (i + 1 < s.size()) n |= static_cast<unsigned char>(s[i + 1]) << 8;
      if (i + 2 < s.size()) n |= static_cast<unsigned char>(s[i + 2]);
      out += k[(n >> 18) & 63];
      out += k[(n >> 12) & 63];
      out += i + 1 < s.size() ? k[(n >> 6) & 63] : '=';
      out += i + 2 < s.size() ? k[n & 63] : '=';
    }
    return out;
  }
  static std::string join(const std::vector<std::string>& v) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + v[i];
    return s + "]";
  }
  std::string write(const std::string& name) const {
    std::string j = "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":" + scenes + ",\"nodes\":" + nodes;
    if (!meshes.empty()) j += ",\"meshes\":" + meshes;
    if (!skins.empty()) j += ",\"skins\":" + skins;
    if (!animations.empty()) j += ",\"animations\":" + animations;
    j += ",\"accessors\":" + join(accessors) + ",\"bufferViews\":" + join(views) +
         ",\"buffers\":[{\"byteLength\":" + std::to_string(bin.size()) +
         ",\"uri\":\"data:application/octet-stream;base64," + base64(bin) + "\"}]}";
    return isochor::test::write_file(isochor::test::temp_dir() / name, j);
  }
};

}  // namespace isochor::test
