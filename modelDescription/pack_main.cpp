// mfbd-pack: scene.json -> self-contained FMI 2.0 Co-Simulation .fmu
//   modelDescription.xml       from the scene's variable table
//   resources/scene.json       the scene, verbatim (its hash is the GUID)
//   resources/visual/<file>    mesh files (STL, OBJ) named by the bodies' "visual"
//   binaries/linux64/<id>.so   the FMU binary of each platform built (or asked
//   binaries/win64/<id>.dll    for), renamed to the model identifier
//   documentation/licenses/    the licences of the libraries in the binaries
//                              (the binaries folder's licenses/)
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "model_description.hpp"
#include "zip_writer.hpp"

#ifndef MFBD_FMU_BINARY_ROOT
#define MFBD_FMU_BINARY_ROOT ""
#endif

namespace fs = std::filesystem;

namespace {

const char* kUsage =
    "usage: mfbd-pack SCENE.json -o OUT.fmu [--platform NAME] [--binaries DIR]\n"
    "       mfbd-pack --guid SCENE.json   (print the GUID an FMU of this scene gets)\n"
    "  --platform NAME  linux64, win64 or all (default): the platforms whose binary\n"
    "                   the FMU carries; all = every one built\n"
    "  --binaries DIR   folder with one subfolder per platform: linux64/mfbd_fmu.so,\n"
    "                   win64/mfbd_fmu.dll (default: " MFBD_FMU_BINARY_ROOT ")\n";

// FMI 2.0 platform folder and the binary's file extension there.
struct Platform {
  const char* name;
  const char* extension;
};
const Platform kPlatforms[] = {{"linux64", ".so"}, {"win64", ".dll"}};

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

// binaries/<platform>/<id><ext> for each platform asked for ("all": each
// one built); an asked platform that is not built is an error.
void addBinaries(const fs::path& root, const std::string& asked, const std::string& id,
                 std::vector<mfbd::ZipEntry>& entries) {
  std::string names;
  bool known = false, any = false;
  for (const Platform& p : kPlatforms) {
    names += names.empty() ? p.name : std::string(", ") + p.name;
    if (asked != "all" && asked != p.name) continue;
    known = true;
    const fs::path binary = root / p.name / (std::string("mfbd_fmu") + p.extension);
    if (!fs::is_regular_file(binary)) {
      if (asked == "all") continue;
      throw std::runtime_error("--platform " + asked + ": no " + binary.string() +
                               " (build it first; README, Platforms)");
    }
    entries.push_back({std::string("binaries/") + p.name + "/" + id + p.extension, readFile(binary)});
    any = true;
  }
  if (!known) throw std::runtime_error("--platform '" + asked + "': expected all, " + names);
  if (!any)
    throw std::runtime_error("binaries folder '" + root.string() + "' has no FMU binary (build the project first)");
}

// documentation/licenses/<file> for each file of the binaries folder's
// licenses/: the binaries link LGPL code (KLU), whose licence goes with them.
void addLicenses(const fs::path& root, std::vector<mfbd::ZipEntry>& entries) {
  const fs::path dir = root / "licenses";
  if (!fs::is_directory(dir))
    throw std::runtime_error("binaries folder '" + root.string() +
                             "' has no licenses/ (the licences of the libraries in the binaries; build the project)");
  std::vector<fs::path> files;
  for (const auto& file : fs::directory_iterator(dir))
    if (file.is_regular_file()) files.push_back(file.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files)
    entries.push_back({"documentation/licenses/" + file.filename().string(), readFile(file)});
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath, outPath, binaries = MFBD_FMU_BINARY_ROOT, platform = "all";
  bool printGuid = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-o" && i + 1 < argc) outPath = argv[++i];
    else if (a == "--guid") printGuid = true;
    else if (a == "--binaries" && i + 1 < argc) binaries = argv[++i];
    else if (a == "--platform" && i + 1 < argc) platform = argv[++i];
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
    std::unique_ptr<mfbd::Simulation> check;
    try {
      scene = mfbd::parseScene(text);
      check = std::make_unique<mfbd::Simulation>(scene);  // what the binary will do at instantiate
    } catch (const mfbd::SceneError& e) {
      std::cerr << scenePath << ": " << e.what() << "\n";
      return 1;
    }
    for (const std::string& note : scene.notes) std::cout << "mfbd-pack: " << note << "\n";
    const std::string id = scene.name;
    const auto table = mfbd::variableTable(scene, check->numbering());
    mfbd::Capabilities caps;
    std::vector<mfbd::ZipEntry> entries;
    entries.push_back({"modelDescription.xml",
                       mfbd::modelDescriptionXml(scene, table, mfbd::sceneGuid(text), id, caps)});
    entries.push_back({"resources/scene.json", text});
    for (auto& mesh : visualMeshFiles(text, fs::path(scenePath).parent_path())) entries.push_back(std::move(mesh));
    addBinaries(binaries, platform, id, entries);
    addLicenses(binaries, entries);
    mfbd::writeZip(outPath, entries);
    std::cout << "mfbd-pack: wrote " << outPath << " (" << table.size() << " variables)\n";
  } catch (const std::exception& e) {
    std::cerr << "mfbd-pack: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
