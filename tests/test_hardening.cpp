// Issue 14's regression tests for the shared pieces: the numeric validation layer, files read and
// written the one way, YAML duplicate keys, and the flight writer that cannot write memory or NaN.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/cli.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/numbers.hpp"
#include "flight/flight.hpp"
#include "support.hpp"

using dw::InputError;
using dw::Range;
using dw::test::TempDir;
namespace fs = std::filesystem;

namespace {
template <class F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const std::exception& e) {
        return e.what();
    }
    return "(no error)";
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string slurp(const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

TEST(Range, NaNAndInfinityAreNeverInside) {
    const Range wide{-1e308, 1e308};
    EXPECT_FALSE(wide.contains(kNaN));
    EXPECT_FALSE(wide.contains(kInf));
    EXPECT_FALSE(wide.contains(-kInf));
    EXPECT_TRUE(wide.contains(0));
    EXPECT_TRUE((Range{0, 1}).contains(1));
    EXPECT_FALSE((Range{0, 1}).contains(1.0000001));
}

TEST(Range, ErrorNamesTheOptionAndTheRange) {
    EXPECT_EQ(error_of([] {
                  dw::require_in(7, Range{0, 1.4, "m"}, "--altitudes");
              }),
              "--altitudes: 7 is not in [0, 1.4] m");
    EXPECT_EQ(error_of([] {
                  dw::require_in(kNaN, Range{0.05, 3, "m/s"}, "--speed");
              }),
              "--speed: nan is not a finite number (expected [0.05, 3] m/s)");
}

TEST(Range, NumberListsAreCheckedItemByItem) {
    const Range r{0, 1.4, "m"};
    EXPECT_EQ(dw::parse_number_list("0.3,0.8", r, "--altitudes"), (std::vector<double>{0.3, 0.8}));
    for (const char* bad : {"nan", "0.3,nan", "inf", "", "0.3,", "1e999", "0.3x", "2"}) {
        EXPECT_NE(error_of([&] { dw::parse_number_list(bad, r, "--altitudes"); }), "(no error)") << bad;
    }
}

TEST(Cli, NumericOptionsRefuseNaNInfinityAndOutOfRange) {
    for (const char* value : {"nan", "inf", "-inf", "-1", "1e400", "3.5", "x", ""}) {
        CLI::App app;
        dw::cli::BaseOptions base;
        dw::cli::configure(app, base);
        double speed = 1;
        app.add_option("--speed", speed)->check(dw::cli::in(Range{0.05, 3, "m/s"}));
        std::vector<std::string> args{"prog", "--speed", value};
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        const std::string e = error_of([&] { dw::cli::parse(app, static_cast<int>(argv.size()), argv.data()); });
        EXPECT_NE(e.find("--speed"), std::string::npos) << value << ": " << e;
        EXPECT_EQ(speed, 1) << value;
    }
}

TEST(Cli, ANumericOptionWithoutARangeIsAProgramError) {
    CLI::App app;
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    double unchecked = 0;
    app.add_subcommand("sub")->add_option("--unchecked", unchecked);
    char prog[] = "prog";
    char* argv[] = {prog};
    EXPECT_NE(error_of([&] { dw::cli::parse(app, 1, argv); }).find("--unchecked"), std::string::npos);
}

TEST(Cli, ConfigMustBeAReadableFile) {
    TempDir dir;
    for (const std::string& path : {dir.file(""), dir.file("missing.yaml")}) {
        CLI::App app;
        dw::cli::BaseOptions base;
        dw::cli::configure(app, base);
        std::vector<std::string> args{"prog", "--config", path};
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        const std::string e = error_of([&] { dw::cli::parse(app, 3, argv.data()); });
        EXPECT_EQ(e.rfind("--config ", 0), 0u) << e;
    }
}

TEST(Files, DirectoriesAndMissingFilesAreOneClearLine) {
    TempDir dir;
    EXPECT_EQ(error_of([&] { dw::read_file(dir.file(""), "--physics"); }),
              "--physics " + dir.file("") + ": is a directory, expected a file");
    EXPECT_EQ(error_of([&] { dw::read_file(dir.file("nope"), "--physics"); }),
              "--physics " + dir.file("nope") + ": no such file");
}

TEST(Files, AFailedWriteLeavesNothingBehind) {
    TempDir dir;
    fs::create_directories(dir.file("ro"));
    ::chmod(dir.file("ro").c_str(), 0555);
    if (::geteuid() != 0) {  // root writes anywhere: the permission case only means something as a user
        EXPECT_THROW(dw::write_file(dir.file("ro/out.txt"), "x"), dw::RuntimeError);
        EXPECT_TRUE(fs::is_empty(dir.file("ro")));
    }
    dw::write_file(dir.file("plain"), "x");
    EXPECT_THROW(dw::write_file(dir.file("plain/out.txt"), "x"), dw::RuntimeError);  // a file as a folder
    dw::write_file(dir.file("new/ok.txt"), "hello");
    EXPECT_EQ(slurp(dir.file("new/ok.txt")), "hello");
    EXPECT_EQ(std::distance(fs::directory_iterator(dir.file("")), fs::directory_iterator()), 3);  // ro/, plain, new/
    EXPECT_EQ(std::distance(fs::directory_iterator(dir.file("new")), fs::directory_iterator()),
              1);  // no temporary left
}

TEST(Files, WritablePathCheckRefusesDirectoriesAndFilesAsFolders) {
    TempDir dir;
    dw::write_file(dir.file("plain"), "x");
    EXPECT_THROW(dw::require_writable_path(dir.file(""), "--out"), InputError);
    EXPECT_THROW(dw::require_writable_path(dir.file("plain/x.yaml"), "--out"), InputError);
    EXPECT_NO_THROW(dw::require_writable_path(dir.file("x.yaml"), "--out"));
    EXPECT_THROW(dw::require_writable_path(dir.file("new/x.yaml"), "--out"), InputError);  // a missing folder
    EXPECT_THROW(dw::require_writable_path("", "--out"), InputError);
    EXPECT_NO_THROW(dw::require_output_dir(dir.file("new/deeper"), "--out"));
    EXPECT_THROW(dw::require_output_dir(dir.file("plain"), "--out"), InputError);
    EXPECT_THROW(dw::require_output_dir("", "--out"), InputError);
    EXPECT_FALSE(fs::exists(dir.file("new")));  // checking creates nothing
}

TEST(Yaml, DuplicateKeysAreAnErrorAtTheSecondKey) {
    const std::string e = error_of([] { dw::load_yaml("a: 1\nb:\n  c: 2\n  c: 3\n", "p.yaml"); });
    EXPECT_EQ(e, "p.yaml:4:3: key 'c' appears twice in the same mapping");
    EXPECT_NO_THROW(dw::load_yaml("a: {c: 1}\nb: {c: 2}\n", "p.yaml"));
}

// Issue 43: a 547-byte alias bomb kept dw-sim busy past two minutes (the key walk expanded the
// aliases), a second document was silently ignored, and nesting deep enough ends a recursive parser.
TEST(Yaml, AliasBombsSecondDocumentsAndDeepNestingAreRefusedInOneLine) {
    std::string prev = "a";
    std::string bomb = "a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n";
    for (char c = 'b'; c <= 'i'; ++c) {
        const std::string name(1, c);
        bomb += name + ": &" + name + " [";
        for (int k = 0; k < 9; ++k) bomb += (k ? ", *" : "*") + prev;
        bomb += "]\n";
        prev = name;
    }
    const struct {
        std::string text, expect;
    } cases[] = {
        {bomb, "p.yaml: more than"},
        {"format: x\n---\nb: 1\n", "p.yaml:3: a second document (after '---'): one document per file"},
        {"a: " + std::string(100000, '[') + std::string(100000, ']') + "\n", "p.yaml: nests deeper than 64 levels"},
    };
    for (const auto& c : cases) {
        const std::string e = error_of([&] { dw::load_yaml(c.text, "p.yaml"); });
        EXPECT_EQ(e.rfind(c.expect, 0), 0u) << e;
        EXPECT_LE(e.size(), 200u) << e;
    }
    // Found by the file fuzzer: yaml-cpp 0.7 loops forever, allocating, on a ',' beginning a value
    // outside [ ] or { }; refused before it parses.
    for (const std::string text : {",\n", "- 1\n,\n", "[1],\n", "# a comment\n,x: 1\n"})
        EXPECT_NE(error_of([&] { dw::load_yaml(text, "p.yaml"); }).find("a ',' that begins a value"), std::string::npos)
            << text;
    EXPECT_NO_THROW(dw::load_yaml("a: v1,v2\nb: [1, 2]\nc: 'x, y'\nd: 1 ,\n", "p.yaml"));
    // A block scalar's lines are text: one that begins with ',' is valid YAML, and read as such;
    // the YAML after the block is checked again.
    const auto block = dw::load_yaml("notes: |\n  , first\n\n  ,second\nb: >-\n    ,x\nc: 1\n", "p.yaml");
    EXPECT_EQ(block["notes"].as<std::string>(), ", first\n\n,second\n");
    EXPECT_EQ(block["b"].as<std::string>(), ",x");
    EXPECT_EQ(block["c"].as<int>(), 1);
    EXPECT_NE(error_of([] { dw::load_yaml("notes: |\n  text\n,\n", "p.yaml"); }).find("p.yaml:3: a ','"),
              std::string::npos);
    EXPECT_NO_THROW(dw::load_yaml("a: &x {b: 1}\nc: *x\n", "p.yaml"));  // an alias as such is fine
    EXPECT_NO_THROW(dw::load_yaml("", "p.yaml"));                       // empty: no settings
}

// Issue 73: one CSV row writer: numbers as csv_cell writes them (a non-finite one an empty cell,
// never "nan"), text and counts as they are, empty cells where asked.
TEST(Numbers, ACsvRowIsItsCellsInOrder) {
    EXPECT_EQ(dw::CsvRow().text("a").num(0.1234567).count(-3).empty(2).num(NAN).num(1.5, 2).line(),
              "a,0.123457,-3,,,,1.5\n");
    EXPECT_EQ(dw::CsvRow().num(INFINITY).line(), "\n");
    EXPECT_EQ(dw::CsvRow().empty(3).line(), ",,\n");
}

TEST(Numbers, AppendFixedWritesExactlyWhatItFormatted) {
    std::string out = "x";
    dw::append_fixed(out, 1e300, 6, "v");
    EXPECT_EQ(out.size(), 1u + 301u + 7u);
    EXPECT_EQ(out.find_first_not_of("x0123456789."), std::string::npos);
    std::string same;
    dw::append_fixed(same, -0.0125, 6, "v");
    char ref[32];
    std::snprintf(ref, sizeof ref, "%.6f", -0.0125);
    EXPECT_EQ(same, ref);
    EXPECT_THROW(dw::append_fixed(same, kNaN, 6, "v"), InputError);
    EXPECT_THROW(dw::append_fixed(same, -kInf, 6, "v"), InputError);
}

// Finding 1: a value of 1e41 or more put raw process memory into poses.csv / wrench.csv. Since
// issue 43 the flight writer refuses what the reader would (values past the quantity's range), so
// the formatter is checked on its own, and the writer's refusal beside it.
TEST(FlightWriter, HugeValuesAreWrittenAsNumbersNotMemory) {
    for (const double v : {1e300, -1e41, 1e41}) {
        std::string out;
        dw::append_fixed(out, v, 6, "value");
        EXPECT_EQ(out.find_first_not_of("0123456789.-"), std::string::npos) << v;
        EXPECT_EQ(std::stod(out), v);
    }
    TempDir dir;
    dw::flight::Flight f;
    f.meta.neighbours = {"v1"};
    const auto s = f.body_index("sufferer"), v = f.body_index("v1");
    f.poses.push_back({0.0, v, {0, 0, -1.7}, {1, 0, 0, 0}});
    f.wrench.push_back({0.0, {1e300, -1e41, 0, 0, 0, 0}});
    f.poses.push_back({0.0, s, {1e41, 0, -1.4}, {1, 0, 0, 0}});
    EXPECT_EQ(error_of([&] { dw::flight::write_flight(f, dir.file("f")); }),
              "flight to write: wrench.csv row 2 column f_n: 1e+300 is not in [-10000, 10000] N");
    EXPECT_FALSE(fs::exists(dir.file("f")));
}

TEST(FlightWriter, NonFiniteValuesAreRefusedAndNoFolderIsLeft) {
    TempDir dir;
    dw::flight::Flight f;
    const auto s = f.body_index("sufferer");
    f.poses.push_back({0.0, s, {0, kNaN, -1.4}, {1, 0, 0, 0}});
    const std::string e = error_of([&] { dw::flight::write_flight(f, dir.file("f")); });
    EXPECT_EQ(e, "flight to write: poses.csv row 2 column e: nan is not a finite number (expected [-1e+06, 1e+06] m)");
    EXPECT_FALSE(fs::exists(dir.file("f")));
}

// Finding 5: a neighbour listed twice counted its force twice.
TEST(FlightReader, ADuplicatedNeighbourIsRefused) {
    TempDir dir;
    dw::flight::Flight f;
    f.meta.neighbours = {"v1"};
    f.poses.push_back({0.0, f.body_index("sufferer"), {0, 0, -1.4}, {1, 0, 0, 0}});
    f.poses.push_back({0.0, f.body_index("v1"), {0, 0, -1.7}, {1, 0, 0, 0}});
    f.wrench.push_back({0.0, {0, 0, 0, 0, 0, 0}});
    dw::flight::write_flight(f, dir.file("f"));
    std::string meta = slurp(dir.file("f/meta.json"));
    meta.replace(meta.find("\"v1\""), 4, "\"v1\", \"v1\"");
    std::ofstream(dir.file("f/meta.json")) << meta;
    EXPECT_NE(error_of([&] { dw::flight::read_flight(dir.file("f")); }).find("'v1' is listed twice"),
              std::string::npos);
}
