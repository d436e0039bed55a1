// Replays a fuzz target's seed corpus, then seeded deterministic mutations of it, through the
// target's LLVMFuzzerTestOneInput (the libFuzzer entry point): the same targets run without clang,
// as CTest tests under the ASan + UBSan job. A crash, a sanitizer report or an exception the
// target does not expect (anything but InputError / InfeasibleError) ends the process: a finding.
//
//   fuzz_TARGET [--runs N] [--seed S] [--max-len BYTES] SEED_FILE_OR_DIR...
//
// With clang the same target file links against libFuzzer instead of this driver
// (tests/fuzz/README.md).
#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes readFile(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Values that break parsers and size fields: limits of the integer widths, and number texts.
const char* const kTokens[] = {"0",    "-1",   "1e308",     "-1e308",     "1e999",      "nan",
                               ".nan", ".inf", "-0",        "2147483647", "4294967297", "[",
                               "{",    "\"",   "\\",        "*a",         "&a ",        "\xff\xfe",
                               "null", "true", "0x7fffffff"};

/// One mutation of `in`, chosen by `rng` (libFuzzer's usual set, reduced).
Bytes mutate(const Bytes& in, std::mt19937_64& rng, std::size_t max_len) {
  Bytes b = in;
  auto pick = [&](std::size_t n) { return n ? static_cast<std::size_t>(rng() % n) : 0; };
  const int rounds = 1 + static_cast<int>(rng() % 4);
  for (int k = 0; k < rounds; ++k) {
    switch (rng() % 9) {
      case 0:  // flip a bit
        if (!b.empty()) b[pick(b.size())] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
        break;
      case 1: {  // an interesting byte
        static const std::uint8_t v[] = {0x00, 0x01, 0x7f, 0x80, 0xff, '\n', '"', '-', '9'};
        if (!b.empty()) b[pick(b.size())] = v[pick(sizeof v)];
        break;
      }
      case 2: {  // a big-endian 32-bit size field
        if (b.size() >= 4) {
          static const std::uint32_t v[] = {0u,          1u,          0x7fffffffu, 0x80000000u,
                                            0xffffffffu, 0x04000000u, 65536u};
          const std::uint32_t x = v[pick(sizeof v / sizeof v[0])];
          const std::size_t at = pick(b.size() - 3);
          for (int i = 0; i < 4; ++i) b[at + i] = static_cast<std::uint8_t>(x >> (24 - 8 * i));
        }
        break;
      }
      case 3: {  // erase a chunk
        if (!b.empty()) {
          const std::size_t at = pick(b.size()),
                            n = 1 + pick(std::min<std::size_t>(64, b.size() - at));
          b.erase(b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(at + n));
        }
        break;
      }
      case 4: {  // duplicate a chunk
        if (!b.empty()) {
          const std::size_t at = pick(b.size()),
                            n = 1 + pick(std::min<std::size_t>(64, b.size() - at));
          const Bytes chunk(b.begin() + static_cast<long>(at),
                            b.begin() + static_cast<long>(at + n));
          b.insert(b.begin() + static_cast<long>(pick(b.size() + 1)), chunk.begin(), chunk.end());
        }
        break;
      }
      case 5: {  // a token
        const char* t = kTokens[pick(sizeof kTokens / sizeof kTokens[0])];
        b.insert(b.begin() + static_cast<long>(pick(b.size() + 1)), t, t + std::strlen(t));
        break;
      }
      case 6: {  // replace a number in the text by a token
        std::size_t at = pick(b.size());
        while (at < b.size() && !(b[at] >= '0' && b[at] <= '9')) ++at;
        std::size_t end = at;
        while (end < b.size() && ((b[end] >= '0' && b[end] <= '9') || b[end] == '.' ||
                                  b[end] == 'e' || b[end] == '-'))
          ++end;
        const char* t = kTokens[pick(sizeof kTokens / sizeof kTokens[0])];
        b.erase(b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(end));
        b.insert(b.begin() + static_cast<long>(at), t, t + std::strlen(t));
        break;
      }
      case 7:  // truncate
        b.resize(pick(b.size() + 1));
        break;
      default:  // random bytes
        for (std::size_t n = 1 + pick(8); n > 0; --n)
          b.insert(b.begin() + static_cast<long>(pick(b.size() + 1)),
                   static_cast<std::uint8_t>(rng()));
        break;
    }
  }
  if (b.size() > max_len) b.resize(max_len);
  return b;
}

/// The input being run, written to ./crash-input (as libFuzzer writes crash-<hash>) if the process
/// dies on it: an uncaught exception (std::terminate) or a fatal signal.
const Bytes* g_current = nullptr;

void writeCurrent() {
  if (g_current == nullptr) return;
  if (std::FILE* f = std::fopen("crash-input", "wb")) {
    std::fwrite(g_current->data(), 1, g_current->size(), f);
    std::fclose(f);
    std::fprintf(stderr, "fuzz driver: the input is in ./crash-input (%zu bytes)\n",
                 g_current->size());
  }
  g_current = nullptr;
}

void onSignal(int sig) {
  writeCurrent();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

int main(int argc, char** argv) {
  std::set_terminate([] {
    writeCurrent();
    std::abort();
  });
  for (int sig : {SIGSEGV, SIGABRT, SIGFPE, SIGBUS, SIGILL}) std::signal(sig, onSignal);
  long runs = 1000;
  unsigned long long seed = 1;
  std::size_t max_len = 1 << 20;
  std::vector<Bytes> corpus;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) {
      runs = std::atol(argv[++i]);
    } else if (a == "--seed" && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--max-len" && i + 1 < argc) {
      max_len = static_cast<std::size_t>(std::atol(argv[++i]));
    } else if (std::filesystem::is_directory(a)) {
      std::vector<std::filesystem::path> files;
      for (const auto& e : std::filesystem::directory_iterator(a))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());  // the same order on every machine
      for (const auto& f : files) corpus.push_back(readFile(f));
    } else if (std::filesystem::is_regular_file(a)) {
      corpus.push_back(readFile(a));
    } else {
      std::fprintf(stderr, "%s: not a seed file or folder\n", a.c_str());
      return 2;
    }
  }
  if (corpus.empty()) {
    std::fprintf(stderr, "usage: %s [--runs N] [--seed S] [--max-len B] SEEDS...\n", argv[0]);
    return 2;
  }
  std::mt19937_64 rng(seed);
  long executions = 0;
  for (const Bytes& s : corpus) {
    g_current = &s;
    LLVMFuzzerTestOneInput(s.data(), s.size());
    ++executions;
  }
  for (long r = 0; r < runs; ++r) {
    const Bytes b = mutate(corpus[static_cast<std::size_t>(r) % corpus.size()], rng, max_len);
    g_current = &b;
    LLVMFuzzerTestOneInput(b.data(), b.size());
    ++executions;
  }
  std::printf("%s: %ld executions (%zu seeds, %ld mutations, seed %llu), no crash\n", argv[0],
              executions, corpus.size(), runs, seed);
  return 0;
}
