// 3MF through lib3mf 1.8 (Debian lib3mf-dev, its v1 C interface): the writer of
// `softevo fabricate OUT.3mf` and the reader of `--check` (fabricate.hpp).
#include <cstdio>
#include <map>
#include <numeric>

#include <nlohmann/json.hpp>

#include "common/input_file.hpp"
#include "common/version.hpp"
#include "fabricate/fabricate.hpp"

#ifdef SOFTEVO_HAVE_LIB3MF
#include <Model/COM/NMR_DLLInterfaces.h>
#endif

namespace softevo::fabricate {

bool have_3mf() {
#ifdef SOFTEVO_HAVE_LIB3MF
  return true;
#else
  return false;
#endif
}

#ifndef SOFTEVO_HAVE_LIB3MF

void write_3mf(const Fabrication&, const std::string& path, Overwrite) {
  throw FabricateError("fabricate: " + path +
                       ": this softevo was built without lib3mf (install lib3mf-dev and "
                       "rebuild); .stl works without it");
}
CheckReport check_3mf(const std::string& path) {
  throw FabricateError("fabricate --check " + path +
                       ": this softevo was built without lib3mf (install lib3mf-dev)");
}

#else

namespace {

// One lib3mf handle, released when it goes out of scope.
struct Handle {
  NMR::PLib3MFBase* p = nullptr;
  Handle() = default;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (p) NMR::lib3mf_release(p);
  }
};

// Throws naming `what` and lib3mf's own message when a call failed.
void check(LIB3MFRESULT result, NMR::PLib3MFBase* instance, const std::string& what) {
  if (result == LIB3MF_OK) return;
  std::string message = "error " + std::to_string(result);
  if (instance) {
    DWORD code = 0;
    LPCSTR text = nullptr;
    if (NMR::lib3mf_getlasterror(instance, &code, &text) == LIB3MF_OK && text) message = text;
  }
  throw FabricateError(what + ": lib3mf: " + message);
}

std::string mm_triple(const Eigen::Vector3d& v) {
  char text[96];
  std::snprintf(text, sizeof text, "%.6g %.6g %.6g", v.x() * 1e3, v.y() * 1e3, v.z() * 1e3);
  return text;
}

}  // namespace

void write_3mf(const Fabrication& fab, const std::string& path, Overwrite overwrite) {
  AtomicOutput out(path, overwrite);
  const std::string what = "fabricate: " + path;
  Handle model;
  check(NMR::lib3mf_createmodel(&model.p), nullptr, what);
  check(NMR::lib3mf_model_setunit(model.p, NMR::MODELUNIT_MILLIMETER), model.p, what);
  const Provenance& pv = fab.provenance;
  // Metadata: lib3mf 1.8 keeps only the well-known names of the 3MF core (it cannot declare a
  // namespace for names of our own, and its reader drops names without one), so softevo's
  // fields are lines "key: value" of the Description.
  std::string description = fab.summary();
  auto field = [&](const std::string& key, const std::string& value) {
    description += "\n" + key + ": " + value;
  };
  field("robot", pv.name);
  if (pv.genome_id) field("genome_id", std::to_string(*pv.genome_id));
  if (pv.generation) field("generation", std::to_string(*pv.generation));
  if (!pv.run.empty()) field("run", pv.run);
  if (!pv.config_hash.empty()) field("config_hash", pv.config_hash);
  char number[40];
  if (pv.fitness) {
    std::snprintf(number, sizeof number, "%.17g", *pv.fitness);
    field("fitness", number);
  }
  field("softevo_version", kVersion);
  std::snprintf(number, sizeof number, "%.17g", fab.voxel_size);
  field("voxel_size_m", number);
  std::snprintf(number, sizeof number, "%.17g", fab.options.channel_diameter);
  field("channel_diameter_m", number);
  static const char* kDirection[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  for (const Inlet& in : fab.inlets) {
    field("inlet " + std::to_string(in.chamber),
          "chamber " + std::to_string(in.chamber) + " at " + mm_triple(in.mouth) + " mm, " +
              kDirection[in.face] + " through " + std::to_string(in.wall_cells) + " wall voxels");
  }
  std::vector<std::pair<std::string, std::string> > meta;
  if (!pv.name.empty()) meta.emplace_back("Title", pv.name);
  meta.emplace_back("Application", std::string("softevo ") + kVersion);
  meta.emplace_back("Description", description);
  for (const auto& [key, value] : meta) {
    check(NMR::lib3mf_model_addmetadatautf8(model.p, key.c_str(), value.c_str()), model.p,
          what + ": metadata " + key);
  }
  // One base material per group, coloured as softevo render colours it.
  Handle materials;
  check(NMR::lib3mf_model_addbasematerialgroup(model.p, &materials.p), model.p, what);
  DWORD materials_id = 0;
  check(NMR::lib3mf_resource_getresourceid(materials.p, &materials_id), materials.p, what);
  for (const MaterialGroup& g : fab.groups) {
    DWORD index = 0;
    check(NMR::lib3mf_basematerial_addmaterialutf8(materials.p, g.name.c_str(), g.colour[0],
                                                   g.colour[1], g.colour[2], &index),
          materials.p, what);
    Handle object;
    check(NMR::lib3mf_model_addmeshobject(model.p, &object.p), model.p, what);
    check(NMR::lib3mf_object_setnameutf8(object.p, g.name.c_str()), object.p, what);
    const std::string part = "material " + std::to_string(g.material) + ", " + g.name;
    check(NMR::lib3mf_object_setpartnumberutf8(object.p, part.c_str()), object.p, what);
    std::vector<NMR::MODELMESHVERTEX> vertices(g.mesh.vertices.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      for (int a = 0; a < 3; ++a)
        vertices[i].m_fPosition[a] = static_cast<float>(g.mesh.vertices[i][a] * 1e3);
    }
    std::vector<NMR::MODELMESHTRIANGLE> triangles(g.mesh.triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      for (int a = 0; a < 3; ++a) triangles[t].m_nIndices[a] = g.mesh.triangles[t][a];
    }
    check(NMR::lib3mf_meshobject_setgeometry(object.p, vertices.data(),
                                             static_cast<DWORD>(vertices.size()), triangles.data(),
                                             static_cast<DWORD>(triangles.size())),
          object.p, what + ": " + g.name);
    Handle property;
    check(NMR::lib3mf_object_createdefaultpropertyhandler(object.p, &property.p), object.p, what);
    check(NMR::lib3mf_defaultpropertyhandler_setbasematerial(property.p, materials_id, index),
          property.p, what);
    Handle item;
    check(NMR::lib3mf_model_addbuilditem(model.p, object.p, nullptr, &item.p), model.p, what);
  }
  Handle writer;
  check(NMR::lib3mf_model_querywriter(model.p, "3mf", &writer.p), model.p, what);
  check(NMR::lib3mf_writer_writetofileutf8(writer.p, out.temp_path().c_str()), writer.p, what);
  out.commit();
}

namespace {

std::string utf8(LIB3MFRESULT (*get)(NMR::PLib3MFBase*, DWORD, LPSTR, ULONG, ULONG*),
                 NMR::PLib3MFBase* model, DWORD index, const std::string& what) {
  ULONG needed = 0;
  check(get(model, index, nullptr, 0, &needed), model, what);
  std::string text(needed + 1, '\0');
  check(get(model, index, text.data(), needed + 1, &needed), model, what);
  text.resize(needed);
  return text;
}

}  // namespace

CheckReport check_3mf(const std::string& path) {
  const std::string what = "fabricate --check " + path;
  // Checked by name before lib3mf opens it: a FIFO would block its open forever, and for a file
  // of another kind lib3mf says only "Could not read ZIP file".
  const std::string irregular = not_a_regular_file(path);
  if (irregular == "does not exist") throw FabricateError(what + ": no such file");
  if (!irregular.empty()) throw FabricateError(what + ": " + irregular + ", not a 3MF file");
  const FileMagic magic = file_magic(path);
  if (magic != FileMagic::zip)
    throw FabricateError(what + ": not a 3MF file (a 3MF file is a ZIP package)" +
                         (magic == FileMagic::json ? "; this is JSON: a robot file?"
                          : magic == FileMagic::hdf5 ? "; this is HDF5: a run archive or trace?"
                                                     : ""));
  Handle model;
  check(NMR::lib3mf_createmodel(&model.p), nullptr, what);
  Handle reader;
  check(NMR::lib3mf_model_queryreader(model.p, "3mf", &reader.p), model.p, what);
  check(NMR::lib3mf_reader_readfromfileutf8(reader.p, path.c_str()), reader.p, what);
  DWORD unit = 0;
  check(NMR::lib3mf_model_getunit(model.p, &unit), model.p, what);
  const double metres = unit == NMR::MODELUNIT_MICROMETER ? 1e-6
                        : unit == NMR::MODELUNIT_MILLIMETER ? 1e-3
                        : unit == NMR::MODELUNIT_CENTIMETER ? 1e-2
                        : unit == NMR::MODELUNIT_INCH ? 0.0254
                        : unit == NMR::MODELUNIT_FOOT ? 0.3048
                                                      : 1.0;
  CheckReport report;
  DWORD count = 0;
  check(NMR::lib3mf_model_getmetadatacount(model.p, &count), model.p, what);
  for (DWORD i = 0; i < count; ++i) {
    report.metadata.emplace_back(utf8(NMR::lib3mf_model_getmetadatakeyutf8, model.p, i, what),
                                 utf8(NMR::lib3mf_model_getmetadatavalueutf8, model.p, i, what));
  }
  Handle objects;
  check(NMR::lib3mf_model_getmeshobjects(model.p, &objects.p), model.p, what);
  BOOL more = false;
  check(NMR::lib3mf_resourceiterator_movenext(objects.p, &more), objects.p, what);
  while (more) {
    Handle object;
    check(NMR::lib3mf_resourceiterator_getcurrent(objects.p, &object.p), objects.p, what);
    CheckedObject o;
    ULONG needed = 0;
    check(NMR::lib3mf_object_getnameutf8(object.p, nullptr, 0, &needed), object.p, what);
    o.name.assign(needed + 1, '\0');
    check(NMR::lib3mf_object_getnameutf8(object.p, o.name.data(), needed + 1, &needed), object.p,
          what);
    o.name.resize(needed);
    DWORD nv = 0, nt = 0;
    check(NMR::lib3mf_meshobject_getvertexcount(object.p, &nv), object.p, what);
    check(NMR::lib3mf_meshobject_gettrianglecount(object.p, &nt), object.p, what);
    o.vertices = nv;
    o.triangles = nt;
    BOOL manifold = false;
    check(NMR::lib3mf_meshobject_ismanifoldandoriented(object.p, &manifold), object.p, what);
    o.manifold_and_oriented = manifold;
    std::vector<NMR::MODELMESHVERTEX> v(nv);
    std::vector<NMR::MODELMESHTRIANGLE> t(nt);
    if (nv > 0)
      check(NMR::lib3mf_meshobject_getvertices(object.p, v.data(), nv, nullptr), object.p, what);
    if (nt > 0)
      check(NMR::lib3mf_meshobject_gettriangleindices(object.p, t.data(), nt, nullptr), object.p,
            what);
    // Shells: triangles joined through shared vertices; each shell's signed volume.
    std::vector<DWORD> parent(nv);
    std::iota(parent.begin(), parent.end(), 0U);
    auto find = [&](DWORD a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    for (const auto& tri : t) {
      for (int a = 1; a < 3; ++a) parent[find(tri.m_nIndices[a])] = find(tri.m_nIndices[0]);
    }
    std::map<DWORD, double> shell_volume;
    for (const auto& tri : t) {
      Eigen::Vector3d p[3];
      for (int a = 0; a < 3; ++a) {
        const auto& pos = v[tri.m_nIndices[a]].m_fPosition;
        p[a] = Eigen::Vector3d(pos[0], pos[1], pos[2]) * metres;
      }
      const double tet = p[0].dot(p[1].cross(p[2])) / 6.0;
      shell_volume[find(tri.m_nIndices[0])] += tet;
      o.volume += tet;
    }
    o.shells = static_cast<int>(shell_volume.size());
    for (const auto& [root, volume] : shell_volume) o.cavities += volume < 0;
    report.objects.push_back(o);
    check(NMR::lib3mf_resourceiterator_movenext(objects.p, &more), objects.p, what);
  }
  return report;
}

#endif

std::string CheckReport::json() const {
  nlohmann::ordered_json j;
  j["metadata"] = nlohmann::ordered_json::object();
  for (const auto& [k, v] : metadata) j["metadata"][k] = v;
  j["objects"] = nlohmann::ordered_json::array();
  for (const auto& o : objects) {
    j["objects"].push_back({{"name", o.name},
                            {"vertices", o.vertices},
                            {"triangles", o.triangles},
                            {"manifold_and_oriented", o.manifold_and_oriented},
                            {"volume_mm3", o.volume * 1e9},
                            {"shells", o.shells},
                            {"cavities", o.cavities}});
  }
  return j.dump();
}

std::string CheckReport::text() const {
  std::string out;
  for (const auto& [k, v] : metadata) out += k + ": " + v + "\n";
  for (const auto& o : objects) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "object %s: %u vertices, %u triangles, %s, volume %.6g mm^3, %d shells "
                  "(%d cavities)\n",
                  o.name.c_str(), o.vertices, o.triangles,
                  o.manifold_and_oriented ? "manifold and oriented" : "NOT manifold and oriented",
                  o.volume * 1e9, o.shells, o.cavities);
    out += line;
  }
  return out;
}

}  // namespace softevo::fabricate
