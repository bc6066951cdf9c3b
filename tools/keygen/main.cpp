// picksight-keygen: writes a new CURVE key pair as NAME.key (public, 0644)
// and NAME.key_secret (public and secret, 0600), the files the video
// server, picksight-vision and picksight-cam read (docs/SECURITY.md).
#include <sys/stat.h>
#include <sys/types.h>

#include <filesystem>
#include <iostream>
#include <string>

#include "picksight/cli/command_line.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/transport/curve_keys.hpp"

namespace {

// Writes atomically, the file's mode 0644 less `umask_bits`: the umask
// decides the mode of the temporary file from its creation on, so a secret is never readable by
// others, not even for a moment (this tool has one thread).
picksight::Result<void> writeWithMode(const std::string& path, const std::string& text,
                                      mode_t umask_bits) {
  const mode_t previous = ::umask(umask_bits);
  auto ok = picksight::writeFileAtomically(path, text);
  ::umask(previous);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  std::string name;
  std::string dir = ".";
  bool force = false;
  picksight::cli::App app(
      "Generates a ZeroMQ CURVE key pair: NAME.key holds the public key (give it to the\n"
      "peers), NAME.key_secret both keys (keep it on this host, mode 0600).",
      "picksight-keygen");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("NAME", name, "base name of the two files (e.g. server, or a client's name)")
      ->required()
      ->check(picksight::cli::checkValue([](const std::string& v) {
        return v.empty() || v.find('/') != std::string::npos
                   ? "NAME must be a plain file name, got '" + v + "'"
                   : std::string();
      }));
  app.addOption("--dir", dir, "where to write them")->typeName("DIR")->showDefault();
  app.addFlag("--force", force, "replace existing files of that name");
  app.footer("Prints the public key on stdout.");
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;

  const std::string public_path = dir + "/" + name + ".key";
  const std::string secret_path = dir + "/" + name + ".key_secret";
  std::error_code ec;
  for (const std::string& path : {public_path, secret_path}) {
    if (!force && std::filesystem::exists(path, ec)) {
      std::cerr << "picksight-keygen: " << path
                << " exists; give --force to replace it (clients holding the old public key "
                   "will be refused)\n";
      return 1;
    }
  }
  auto keys = picksight::transport::generateKeyPair();
  if (!keys) {
    std::cerr << "picksight-keygen: " << keys.error().message << "\n";
    return 1;
  }
  // The secret first: a public key without its secret is useless.
  if (auto ok = writeWithMode(secret_path, picksight::transport::secretKeyFileText(*keys), 077);
      !ok) {
    std::cerr << "picksight-keygen: " << ok.error().message << "\n";
    return 1;
  }
  if (auto ok = writeWithMode(public_path, picksight::transport::publicKeyFileText(*keys), 022);
      !ok) {
    std::cerr << "picksight-keygen: " << ok.error().message << "\n";
    return 1;
  }
  std::cerr << "picksight-keygen: wrote " << public_path << " and " << secret_path << "\n";
  std::cout << keys->public_key << "\n";
  return 0;
}
