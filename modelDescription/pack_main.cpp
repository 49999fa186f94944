// mfbd-pack: scene.json -> self-contained FMI 2.0 Co-Simulation .fmu
//   modelDescription.xml       from the scene's variable table
//   resources/scene.json       the scene, verbatim (its hash is the GUID)
//   binaries/linux64/<id>.so   the FMU binary of each platform built (or asked
//   binaries/win64/<id>.dll    for), renamed to the model identifier
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

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
    addBinaries(binaries, platform, id, entries);
    mfbd::writeZip(outPath, entries);
    std::cout << "mfbd-pack: wrote " << outPath << " (" << table.size() << " variables)\n";
  } catch (const std::exception& e) {
    std::cerr << "mfbd-pack: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
