// The replay driver: a fuzz target (tests/fuzz/fuzz_X.cpp) linked with this main instead of
// libFuzzer becomes an ordinary test (fuzz_X_replay, ctest label unit), built by any
// compiler and run under ASan+UBSan by scripts/test. It runs LLVMFuzzerTestOneInput on
//   1. the target's generated seeds (registered by LLVMFuzzerInitialize, fuzz_support.hpp),
//   2. every file of the folders (or the files) named on the command line, sorted by name
//      (the committed corpus tests/fuzz/corpus/<X>/, crash inputs saved there included),
//   3. deterministic mutants of each of those: truncations, bit flips, bytes and words
//      overwritten with boundary values, a stretch erased, duplicated or spliced from the
//      next input, so that the replay reaches the decoders' error paths. A target with a
//      custom mutator (checksum repair) also gets each mutant repaired.
// Each input is a fresh heap block of its exact size, so ASan sees reads past the end.
//
//   fuzz_X_replay [--mutants=N] [--verbose] [--artifact-dir=DIR] [--write-seeds=DIR] [PATH...]
//
// --mutants=N: mutants per input (default 1000; 0: inputs only). A property violation or a
// sanitizer report names the input being run and, with --artifact-dir, writes its bytes
// to DIR/crash-<target>-<n> (replay it with `fuzz_X_replay FILE`, or the libFuzzer build).
// Exit status 0 when every input ran; the last line says how many and how long.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tests/fuzz/fuzz_support.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define VISTEL_REPLAY_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VISTEL_REPLAY_ASAN 1
#endif
#endif
#ifdef VISTEL_REPLAY_ASAN
#include <sanitizer/common_interface_defs.h>
#endif

// The target's entry points (LLVMFuzzerInitialize and the custom mutator are optional).
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);
extern "C" __attribute__((weak)) std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data,
                                                                     std::size_t size,
                                                                     std::size_t max_size,
                                                                     unsigned seed);

// libFuzzer's mutator, as custom mutators call it: here the identity, because the replay
// has mutated the input already and only wants the target's repair step.
extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* /*data*/, std::size_t size,
                                        std::size_t /*max_size*/) {
  return size;
}

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Input {
  std::string name;
  Bytes bytes;
};

// ---- reporting a failing input -------------------------------------------------------------

// What is running now, for the signal handler and the sanitizer's death callback (set
// before each run; plain buffers so the handler only reads them).
char g_target[128] = "fuzz target";
char g_current[512] = "(initialising)";
char g_artifact_dir[512] = "";
const std::uint8_t* g_data = nullptr;
std::size_t g_size = 0;
int g_crashes = 0;

void writeAll(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n <= 0) return;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
}

void writeText(const char* text) { writeAll(2, text, std::strlen(text)); }

// Says which input failed and saves it (async-signal-safe: write/open only).
void reportCurrent() {
  writeText("\n");
  writeText(g_target);
  writeText(": failed on input ");
  writeText(g_current);
  writeText("\n");
  if (g_artifact_dir[0] == '\0' || g_data == nullptr) return;
  char path[700];
  const int n =
      std::snprintf(path, sizeof path, "%s/crash-%s-%d", g_artifact_dir, g_target, g_crashes++);
  if (n <= 0 || static_cast<std::size_t>(n) >= sizeof path) return;
  const int fd = ::open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return;
  writeAll(fd, g_data, g_size);
  ::close(fd);
  writeText("the input was saved to ");
  writeText(path);
  writeText("\n");
}

void onFatalSignal(int signal) {
  reportCurrent();
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

void copyName(char* out, std::size_t size, std::string_view text) {
  const std::size_t n = std::min(size - 1, text.size());
  std::memcpy(out, text.data(), n);
  out[n] = '\0';
}

// ---- mutations -----------------------------------------------------------------------------

std::uint64_t mix(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  x ^= x >> 33;
  return x;
}

std::uint64_t hashOf(const Bytes& bytes) {
  std::uint64_t h = 0x9e3779b97f4a7c15ull ^ bytes.size();
  for (std::uint8_t b : bytes) h = (h ^ b) * 0x100000001b3ull;
  return h;
}

// Mutant k of `in` (k = 0, 1, ...): the kinds take turns, and positions spread over the
// input from a hash of its bytes, so different seeds are cut in different places.
Bytes mutant(const Bytes& in, const Bytes& other, std::uint64_t k) {
  static constexpr std::uint8_t kBytes[] = {0x00, 0xff, 0x7f, 0x80, 0x01, 0x20, '"', '\n'};
  static constexpr std::uint32_t kWords[] = {0x00000000u, 0xffffffffu, 0x7fffffffu,
                                             0x80000000u, 0x00010000u, 0x0000ffffu};
  const std::uint64_t r = mix(hashOf(in) + k * 0x9e3779b97f4a7c15ull);
  const std::size_t n = in.size();
  Bytes out = in;
  if (n == 0) {
    out.push_back(kBytes[k % std::size(kBytes)]);
    return out;
  }
  const std::size_t at = static_cast<std::size_t>(r % n);
  const std::size_t span = 1 + static_cast<std::size_t>((r >> 24) % std::min<std::size_t>(n, 64));
  switch (k % 8) {
    case 0: {  // cut: the last byte off, then at eighths of the input, then anywhere
      const std::uint64_t j = k / 8;
      out.resize(j == 0 ? n - 1 : j < 8 ? static_cast<std::size_t>(n * j / 8) : at);
      break;
    }
    case 1:
    case 2:  // one bit
      out[at] ^= static_cast<std::uint8_t>(1u << ((r >> 40) % 8));
      break;
    case 3:  // a boundary byte
      out[at] = kBytes[(r >> 40) % std::size(kBytes)];
      break;
    case 4: {  // a boundary word (sizes, counts)
      const std::uint32_t w = kWords[(r >> 40) % std::size(kWords)];
      for (std::size_t i = 0; i < 4 && at + i < n; ++i)
        out[at + i] = static_cast<std::uint8_t>(w >> (8 * i));
      break;
    }
    case 5:  // a stretch erased
      out.erase(out.begin() + static_cast<std::ptrdiff_t>(at),
                out.begin() + static_cast<std::ptrdiff_t>(std::min(n, at + span)));
      break;
    case 6:  // a stretch repeated
      out.insert(out.begin() + static_cast<std::ptrdiff_t>(at),
                 in.begin() + static_cast<std::ptrdiff_t>(at),
                 in.begin() + static_cast<std::ptrdiff_t>(std::min(n, at + span)));
      break;
    default: {  // spliced: this input's head, the other's tail
      const std::size_t from =
          other.empty() ? 0 : static_cast<std::size_t>((r >> 32) % other.size());
      out.resize(at);
      out.insert(out.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
      break;
    }
  }
  return out;
}

// ---- running -------------------------------------------------------------------------------

std::uint64_t g_runs = 0;
bool g_verbose = false;

void runOne(const Bytes& bytes, const std::string& name) {
  copyName(g_current, sizeof g_current, name);
  // A block of exactly the input's size (ASan catches reads past it).
  std::unique_ptr<std::uint8_t[]> copy(new std::uint8_t[bytes.size()]);
  if (!bytes.empty()) std::memcpy(copy.get(), bytes.data(), bytes.size());
  g_data = copy.get();
  g_size = bytes.size();
  if (g_verbose) std::fprintf(stderr, "%s (%zu bytes)\n", name.c_str(), bytes.size());
  LLVMFuzzerTestOneInput(copy.get(), bytes.size());
  g_data = nullptr;
  ++g_runs;
}

bool readFile(const std::filesystem::path& path, Bytes& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

}  // namespace

int main(int argc, char** argv) {
  const auto start = std::chrono::steady_clock::now();
  copyName(g_target, sizeof g_target, std::filesystem::path(argv[0]).filename().string());
  // A failed check() aborts; under ASan its report ends in the death callback (and its own
  // handler keeps reporting faults), without it the fault handlers name the input.
  std::signal(SIGABRT, onFatalSignal);
#ifdef VISTEL_REPLAY_ASAN
  __sanitizer_set_death_callback(reportCurrent);
#else
  std::signal(SIGSEGV, onFatalSignal);
  std::signal(SIGBUS, onFatalSignal);
  std::signal(SIGFPE, onFatalSignal);
#endif

  // The target's own setup (with --write-seeds=DIR it writes its seeds and exits).
  if (LLVMFuzzerInitialize != nullptr) LLVMFuzzerInitialize(&argc, &argv);

  // Options and paths.
  std::uint64_t mutants = 1000;
  std::vector<std::filesystem::path> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg(argv[i]);
    if (arg.starts_with("--mutants=")) {
      mutants = std::strtoull(argv[i] + 10, nullptr, 10);
    } else if (arg == "--verbose") {
      g_verbose = true;
    } else if (arg.starts_with("--artifact-dir=")) {
      copyName(g_artifact_dir, sizeof g_artifact_dir, arg.substr(15));
      std::error_code ec;
      std::filesystem::create_directories(g_artifact_dir, ec);
    } else if (arg.starts_with("--")) {
      std::fprintf(stderr, "%s: unknown option %s\n", g_target, argv[i]);
      return 2;
    } else {
      paths.emplace_back(arg);
    }
  }

  // Inputs: generated seeds, then the files named (folders: their files, by name).
  std::vector<Input> inputs;
  std::size_t generated = 0;
  if (const auto& make_seeds = vistel::fuzz::registeredSeeds()) {
    copyName(g_current, sizeof g_current, "(generating seeds)");
    for (vistel::fuzz::Seed& seed : make_seeds()) {
      inputs.push_back({"seed:" + seed.name, std::move(seed.bytes)});
      ++generated;
    }
  }
  for (const std::filesystem::path& path : paths) {
    std::error_code ec;
    std::vector<std::filesystem::path> files;
    if (std::filesystem::is_directory(path, ec)) {
      for (const auto& entry : std::filesystem::directory_iterator(path, ec)) {
        if (entry.is_regular_file(ec)) files.push_back(entry.path());
      }
      std::sort(files.begin(), files.end());
    } else {
      files.push_back(path);
    }
    for (const std::filesystem::path& file : files) {
      Input input{file.string(), {}};
      if (!readFile(file, input.bytes)) {
        std::fprintf(stderr, "%s: cannot read %s\n", g_target, file.string().c_str());
        return 2;
      }
      inputs.push_back(std::move(input));
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "%s: no inputs (no generated seeds and no files named)\n", g_target);
    return 2;
  }

  // Every input, then its mutants (raw, and repaired where the target repairs).
  std::size_t largest = 0;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const Input& input = inputs[i];
    largest = std::max(largest, input.bytes.size());
    runOne(input.bytes, input.name);
    const Bytes& other = inputs[(i + 1) % inputs.size()].bytes;
    for (std::uint64_t k = 0; k < mutants; ++k) {
      Bytes m = mutant(input.bytes, other, k);
      const std::string name = input.name + " mutant " + std::to_string(k);
      runOne(m, name);
      if (LLVMFuzzerCustomMutator != nullptr && !m.empty()) {
        const std::size_t n = LLVMFuzzerCustomMutator(m.data(), m.size(), m.size(), 1);
        m.resize(std::min(n, m.size()));
        runOne(m, name + " repaired");
      }
    }
  }

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "%s: %zu inputs (%zu generated, %zu files, largest %zu bytes), %llu runs with "
      "%llu mutants each, %.2f s\n",
      g_target, inputs.size(), generated, inputs.size() - generated, largest,
      static_cast<unsigned long long>(g_runs), static_cast<unsigned long long>(mutants), seconds);
  return 0;
}
