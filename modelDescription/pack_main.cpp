// mfbd-pack: scene.json -> self-contained FMI 2.0 Co-Simulation .fmu
//   modelDescription.xml       from the scene's variable table
//   resources/scene.json       the scene, verbatim (its hash is the GUID)
//   resources/visual/<file>   mesh files (STL, OBJ) named by the bodies' "visual"
//   binaries/linux64/<id>.so   the one FMU binary, renamed to the model identifier,
//                              with every non-runtime library it needs (RUNPATH $ORIGIN)
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "model_description.hpp"
#include "zip_writer.hpp"

#ifndef MFBD_FMU_BINARY_DIR
#define MFBD_FMU_BINARY_DIR ""
#endif

namespace fs = std::filesystem;

namespace {

const char* kUsage =
    "usage: mfbd-pack SCENE.json -o OUT.fmu [--binaries DIR]\n"
    "       mfbd-pack --guid SCENE.json   (print the GUID an FMU of this scene gets)\n"
    "  --binaries DIR  folder with mfbd_fmu.so and the libraries it ships with\n"
    "                  (default: " MFBD_FMU_BINARY_DIR ")\n";

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error(p.string() + ": cannot read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The mesh files that bodies' "visual" entries name (relative to the scene
// file), as resources/visual/<file name>, where the drawing tools look.
std::vector<mfbd::ZipEntry> visualMeshFiles(const std::string& sceneText, const fs::path& sceneDir) {
  const auto doc = nlohmann::json::parse(sceneText);
  std::map<std::string, std::pair<std::string, std::string>> files;  // file name -> (path in the scene, JSON path)
  if (!doc.contains("bodies")) return {};
  for (std::size_t i = 0; i < doc["bodies"].size(); ++i) {
    const auto& body = doc["bodies"][i];
    if (!body.contains("visual")) continue;
    const auto& v = body["visual"];
    const auto items = v.is_array() ? v : nlohmann::json::array({v});
    for (std::size_t k = 0; k < items.size(); ++k) {
      if (!items[k].is_object() || !items[k].contains("file")) continue;
      const std::string where = "bodies[" + std::to_string(i) + "].visual" +
                                (v.is_array() ? "[" + std::to_string(k) + "]" : "") + ".file";
      if (!items[k]["file"].is_string()) throw std::runtime_error(where + ": expected a file name (STL or OBJ)");
      const std::string file = items[k]["file"];
      const std::string name = fs::path(file).filename().string();
      const auto known = files.find(name);
      if (known != files.end() && known->second.first != file)
        throw std::runtime_error(where + ": '" + file + "' has the file name of '" + known->second.first +
                                 "'; mesh files need different names");
      files[name] = {file, where};
    }
  }
  std::vector<mfbd::ZipEntry> entries;
  for (const auto& [name, source] : files) {
    const auto& [file, where] = source;
    const fs::path path = fs::path(file).is_absolute() ? fs::path(file) : sceneDir / file;
    if (!fs::is_regular_file(path))
      throw std::runtime_error(where + ": mesh file '" + file + "' not found (looked at " + path.string() + ")");
    entries.push_back({"resources/visual/" + name, readFile(path)});
  }
  return entries;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath, outPath, binaries = MFBD_FMU_BINARY_DIR;
  bool printGuid = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-o" && i + 1 < argc) outPath = argv[++i];
    else if (a == "--guid") printGuid = true;
    else if (a == "--binaries" && i + 1 < argc) binaries = argv[++i];
    else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    } else if (!a.empty() && a[0] != '-' && scenePath.empty()) scenePath = a;
    else {
      std::cerr << "mfbd-pack: unexpected argument '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (scenePath.empty() || (outPath.empty() && !printGuid)) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    const std::string text = readFile(scenePath);
    if (printGuid) {
      std::cout << mfbd::sceneGuid(text) << "\n";
      return 0;
    }
    mfbd::Scene scene;
    try {
      scene = mfbd::parseScene(text);
      (void)mfbd::assemble(scene);  // what the binary will do at instantiate
    } catch (const mfbd::SceneError& e) {
      std::cerr << scenePath << ": " << e.what() << "\n";
      return 1;
    }
    for (const std::string& note : scene.notes) std::cout << "mfbd-pack: " << note << "\n";
    const std::string id = scene.name;
    const auto table = mfbd::variableTable(scene);
    mfbd::Capabilities caps;
    std::vector<mfbd::ZipEntry> entries;
    entries.push_back({"modelDescription.xml",
                       mfbd::modelDescriptionXml(scene, table, mfbd::sceneGuid(text), id, caps)});
    entries.push_back({"resources/scene.json", text});
    for (auto& mesh : visualMeshFiles(text, fs::path(scenePath).parent_path())) entries.push_back(std::move(mesh));
    const fs::path binDir(binaries);
    if (!fs::is_regular_file(binDir / "mfbd_fmu.so"))
      throw std::runtime_error("binaries folder '" + binaries + "' has no mfbd_fmu.so (build the project first)");
    for (const auto& f : fs::directory_iterator(binDir)) {
      if (!f.is_regular_file()) continue;
      const std::string name = f.path().filename() == "mfbd_fmu.so" ? id + ".so" : f.path().filename().string();
      entries.push_back({"binaries/linux64/" + name, readFile(f.path())});
    }
    mfbd::writeZip(outPath, entries);
    std::cout << "mfbd-pack: wrote " << outPath << " (" << table.size() << " variables)\n";
  } catch (const std::exception& e) {
    std::cerr << "mfbd-pack: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
