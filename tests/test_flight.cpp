// Flight folders (downwash-flight/1): round trip, and every rule enforced with file:line.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "flight/flight.hpp"
#include "support.hpp"

using namespace dw::flight;

namespace {
Flight sample_flight() {
    Flight f;
    f.meta.neighbours = {"v1"};
    f.meta.formation = "single";
    f.meta.vehicles["v1"] = VehicleInfo{};
    const auto s = f.body_index("sufferer"), v = f.body_index("v1");
    for (int i = 0; i < 10; ++i) {
        f.wrench.push_back({0.0125 * i, {0.1 * i, -0.2, 1.5, 0.01, -0.02, 0.003}});
        f.poses.push_back({i / 180.0, s, {0, 0, -1.4}, {1, 0, 0, 0}});
        f.poses.push_back({i / 180.0, v, {0.1, 0.2 * i, -1.7}, {0.70710678, 0, 0, 0.70710678}});
    }
    f.legs = std::vector<Leg>{{0, 0.01, 0.04}};
    return f;
}

// A valid wrench.csv header and n rows at t = 0.
std::string many_rows(int n) {
    std::string s = "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n";
    for (int i = 0; i < n; ++i) s += "0,1,2,3,4,5,6\n";
    return s;
}

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string error_reading(const std::string& dir) {
    try {
        read_flight(dir);
    } catch (const dw::InputError& e) {
        return e.what();
    }
    return "(no error)";
}
}  // namespace

TEST(FlightFolder, RoundTripsAndKeepsUnknownMetaKeys) {
    dw::test::TempDir d;
    Flight f = sample_flight();
    f.meta.extra_json = R"({"lab":"Cambridge","notes":{"wind":0}})";
    f.meta.clock_offset_measured_s = 0.0123456789012345;  // the lab's measured timing: numbers end to end
    f.meta.stand_pipeline_delay_s = 0.004;
    write_flight(f, d.file("f"));
    const Flight g = read_flight(d.file("f"));
    EXPECT_EQ(g.meta.clock_offset_measured_s, f.meta.clock_offset_measured_s);
    EXPECT_EQ(g.meta.stand_pipeline_delay_s, f.meta.stand_pipeline_delay_s);
    EXPECT_EQ(g.meta.extra_json.find("measured"), std::string::npos) << "a typed key, not an extra one";
    EXPECT_EQ(g.meta.neighbours, f.meta.neighbours);
    EXPECT_EQ(g.bodies, f.bodies);
    ASSERT_EQ(g.wrench.size(), 10u);
    EXPECT_NEAR(g.wrench[3].w[0], 0.3, 1e-9);
    ASSERT_EQ(g.poses.size(), 20u);
    EXPECT_NEAR(g.poses[5].p[1], 0.4, 1e-9);
    ASSERT_TRUE(g.legs.has_value());
    EXPECT_EQ(g.legs->size(), 1u);
    EXPECT_NE(g.meta.extra_json.find("Cambridge"), std::string::npos);
    EXPECT_EQ(g.meta.pose_source, dw::flight::PoseSource::motion_capture) << "the default, not written";
    EXPECT_EQ(dw::read_file(d.file("f/meta.json")).find("pose_source"), std::string::npos);
    // Poses from the vehicles' own estimates (issue 42) are said so, and read back.
    f.meta.pose_source = dw::flight::PoseSource::estimate;
    write_flight(f, d.file("e"));
    EXPECT_EQ(read_flight(d.file("e")).meta.pose_source, dw::flight::PoseSource::estimate);
    // Writing what was read gives the same bytes.
    write_flight(g, d.file("g"));
    for (const char* name : {"meta.json", "wrench.csv", "poses.csv", "legs.csv"}) {
        EXPECT_EQ(dw::read_file(d.file(std::string("f/") + name)), dw::read_file(d.file(std::string("g/") + name)))
            << name;
    }
}

TEST(FlightFolder, LegsAreOptional) {
    dw::test::TempDir d;
    Flight f = sample_flight();
    f.legs.reset();
    write_flight(f, d.file("f"));
    EXPECT_FALSE(read_flight(d.file("f")).legs.has_value());
}

TEST(FlightFolder, EveryRuleIsEnforcedWithFileAndLine) {
    dw::test::TempDir d;
    const std::string dir = d.file("f");
    auto fresh = [&] { write_flight(sample_flight(), dir); };
    struct Case {
        const char* file;
        std::string text;
        std::string expect;
    };
    const std::vector<Case> cases = {
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch\n0,1,2,3,4,5\n",
         "wrench.csv:1: header is 't,f_n,f_e,f_d,m_roll,m_pitch'"},
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5\n",
         "wrench.csv:3: 6 fields, expected 7"},
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1,2,3,4,5,6\n0.1,1,2,3,4,abc,6\n",
         "wrench.csv:3: column m_pitch: 'abc' is not a number"},
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1e308,2,3,4,5,6\n",
         "wrench.csv:2: column f_n: 1e+308 is not in [-10000, 10000] N"},
        {"poses.csv", "t,body,n,e,d,qw,qx,qy,qz\n0,sufferer,0,0,-1e9,1,0,0,0\n",
         "poses.csv:2: column d: -1e+09 is not in [-1e+06, 1e+06] m"},
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5,nan\n",
         "wrench.csv:3: column m_yaw: nan is not a finite number"},
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0.2,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n",
         "wrench.csv:3: t = 0.1 is earlier"},
        {"wrench.csv",
         "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n0.2,1,2,3,4,5,6\n0.3;1;2;3;4;5;6\n",
         "wrench.csv:5: 1 fields, expected 7"},
        {"wrench.csv",
         "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n0.2,1,2,3,4,5,6\n0.3,1,2,3,4,5,6,7\n",
         "wrench.csv:5: 8 fields"},
        {"wrench.csv",
         "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n0.2,1,2,3,4,5,6\n0.3,1,2,3,4,5,6\n0.4,1,"
         "2,3,,5,6\n",
         "wrench.csv:6: column m_roll: '' is not a number"},
        {"wrench.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n", "wrench.csv:1: no samples"},
        {"poses.csv", "t,body,n,e,d,qw,qx,qy,qz\n0,sufferer,0,0,-1.4,1,0,0,0\n0,v1,0,0,-1.7,0.5,0,0,0\n",
         "poses.csv:3: quaternion norm 0.5 is not 1"},
        {"poses.csv", "t,body,n,e,d,qw,qx,qy,qz\n0,sufferer,0,0,-1.4,1,0,0,0\n",
         "poses.csv:1: neighbour 'v1' named in meta.json has no pose"},
        {"poses.csv", "t,body,n,e,d,qw,qx,qy,qz\n0,,0,0,-1.4,1,0,0,0\n", "poses.csv:2: column body: empty"},
        {"legs.csv", "leg,t_start,t_end\n0,0.5,0.2\n", "legs.csv:2: t_end is not after t_start"},
        {"legs.csv", "leg,t_start,t_end\n0.5,0.1,0.2\n", "legs.csv:2: column leg: '0.5' is not a leg number"},
        {"meta.json", "{\"format\": \"downwash-flight/2\"}",
         "meta.json: field 'format': expected \"downwash-flight/1\""},
        {"meta.json",
         "{\"format\": \"downwash-flight/1\", \"sufferer\": \"sufferer\", \"neighbours\": [\"v1\"], \"formation\": "
         "\"triangle\"}",
         "meta.json: field 'formation': 'triangle' is not one of"},
        {"meta.json", "{\"format\": \"downwash-flight/1\",\n \"sufferer\": }", "meta.json:2:14: not valid JSON"},
        {"meta.json",
         "{\"format\": \"downwash-flight/1\", \"sufferer\": \"sufferer\", \"neighbours\": [\"v1\"], \"formation\": "
         "\"single\", \"vehicles\": {\"v1\": {\"mass_kg\": -1}}}",
         "meta.json: field 'vehicles.v1.mass_kg': -1 is not in [0.01, 100] kg"},
        {"meta.json",
         "{\"format\": \"downwash-flight/1\", \"sufferer\": \"sufferer\", \"neighbours\": [\"v1\"], \"formation\": "
         "\"single\", \"pose_source\": \"gps\"}",
         "meta.json: field 'pose_source': \"gps\" is not motion_capture or estimate"},
        {"wrench.csv", many_rows(120) + "1e400,1,2,3,4,5,6\n", "wrench.csv:122: column t: '1e400' is not a number"},
        {"wrench.csv", many_rows(14) + "0.5,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n", "wrench.csv:17: t = 0.1 is earlier"},
    };
    for (const auto& c : cases) {
        fresh();
        write(dir + "/" + c.file, c.text);
        const std::string e = error_reading(dir);
        EXPECT_NE(e.find(c.expect), std::string::npos)
            << c.file << ": got '" << e << "', expected '" << c.expect << "'";
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
    fresh();
    std::filesystem::remove(dir + "/poses.csv");
    EXPECT_NE(error_reading(dir).find("poses.csv: no such file"), std::string::npos);
    EXPECT_NE(error_reading(d.file("nothing")).find("not a flight folder"), std::string::npos);
}

// Issue 41: reference.csv, another model's prediction of the wrench (../shared/FLIGHT_FORMAT.md):
// round trip with empty cells where the model predicts nothing, and every rule located.
TEST(FlightFolder, AReferencePredictionRoundTripsWithEmptyCellsAndItsRulesAreLocated) {
    dw::test::TempDir d;
    Flight f = sample_flight();
    f.meta.reference = ReferenceInfo{"an onboard network", {"f_d"}};
    for (const auto& s : f.wrench) f.reference.push_back({s.t, {NAN, NAN, 0.5 * s.w[2], NAN, NAN, NAN}});
    write_flight(f, d.file("f"));
    const std::string text = dw::read_file(d.file("f/reference.csv"));
    EXPECT_EQ(text.substr(0, text.find('\n', text.find('\n') + 1)),
              "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0.000000,,,0.750000,,,");
    const Flight g = read_flight(d.file("f"));
    ASSERT_TRUE(g.meta.reference.has_value());
    EXPECT_EQ(g.meta.reference->source, "an onboard network");
    ASSERT_EQ(g.reference.size(), f.wrench.size());
    EXPECT_DOUBLE_EQ(g.reference[3].w[2], 0.75);
    EXPECT_TRUE(std::isnan(g.reference[3].w[0]));
    write_flight(g, d.file("g"));
    EXPECT_EQ(dw::read_file(d.file("g/reference.csv")), text);
    EXPECT_EQ(dw::read_file(d.file("g/meta.json")), dw::read_file(d.file("f/meta.json")));

    const std::string dir = d.file("f");
    write(dir + "/reference.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,,,1,,,\n0.1,2,,1,,,\n");
    EXPECT_NE(error_reading(dir).find("reference.csv:3: column f_n: '2' where the reference predicts nothing"),
              std::string::npos)
        << error_reading(dir);
    write(dir + "/reference.csv", "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,,,1,,,\n0.1,,,,,,\n");
    EXPECT_NE(error_reading(dir).find("reference.csv:3: column f_d: '' is not a number"), std::string::npos)
        << error_reading(dir);
    std::filesystem::remove(dir + "/reference.csv");
    EXPECT_NE(error_reading(dir).find("reference.csv"), std::string::npos) << "meta.json names a missing file";
    write_flight(sample_flight(), d.file("h"));
    write(d.file("h/reference.csv"), "t,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n0,,,1,,,\n");
    EXPECT_NE(error_reading(d.file("h")).find("field 'reference': missing, but reference.csv is there"),
              std::string::npos)
        << error_reading(d.file("h"));
    std::string meta = dw::read_file(d.file("h/meta.json"));
    meta.insert(meta.find('{') + 1, R"("reference": {"source": "x", "axes": ["f_z"]},)");
    write(d.file("h/meta.json"), meta);
    EXPECT_NE(error_reading(d.file("h")).find("field 'reference.axes': 'f_z' is not one of"), std::string::npos)
        << error_reading(d.file("h"));
}

// Issue 43: meta.json and legs.csv numbers through the ranges the same quantities have elsewhere,
// and JSON that would crash or overflow a parser refused in one located line.
TEST(FlightFolder, HostileNumbersAndNestingInMetaAndLegsAreOneLocatedLine) {
    dw::test::TempDir d;
    const std::string dir = d.file("f");
    write_flight(sample_flight(), dir);
    const std::string meta = dw::read_file(dir + "/meta.json");
    auto with = [&](const std::string& from, const std::string& to) {
        std::string m = meta;
        const auto at = m.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        m.replace(at, from.size(), to);
        write(dir + "/meta.json", m);
        return error_reading(dir);
    };
    const struct {
        std::string from, to, expect;
    } cases[] = {
        {"\"rotors\": 4", "\"rotors\": 17", "field 'vehicles.v1.rotors': 17 is not in [1, 16]"},
        {"\"rotors\": 4", "\"rotors\": 4294967297", "is not in [1, 16]"},
        {"\"rotors\": 4", "\"rotors\": 2.5", "field 'vehicles.v1.rotors': not an integer"},
        {"\"mass_kg\": 0.7", "\"mass_kg\": 1e9", "is not in [0.01, 100] kg"},
        {"\"mass_kg\": 0.7", "\"mass_kg\": 1e400", "meta.json: not valid JSON:"},
        {"\"formation\"", std::string(100000, '[') + std::string(100000, ']') + ", \"x\"",
         "nests deeper than 64 levels"},
        // Issue 70: the lab's measured timing, kept among the extra keys, is a time a lab could
        // measure (the explainer printed a 1e300 s clock offset in full, 300 digits).
        {"\"formation\"", "\"clock_offset_measured_s\": 1e300, \"formation\"",
         "field 'clock_offset_measured_s': 1e+300 is not in [-3600, 3600] s"},
        {"\"formation\"", "\"clock_offset_measured_s\": \"0.1\", \"formation\"",
         "field 'clock_offset_measured_s': not a number"},
        {"\"formation\"", "\"stand_pipeline_delay_s\": -0.5, \"formation\"",
         "field 'stand_pipeline_delay_s': -0.5 is not in [0, 3600] s"},
    };
    for (const auto& c : cases) {
        const std::string e = with(c.from, c.to);
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.to.substr(0, 40) << " -> " << e;
        EXPECT_LE(e.size(), 200u) << e.substr(0, 300);
    }
    write(dir + "/meta.json", meta);
    write(dir + "/legs.csv", "leg,t_start,t_end\n1000000000000000000,0.01,0.04\n");
    EXPECT_NE(error_reading(dir).find("legs.csv:2: column leg: 1e+18 is not in [0, 1e+06]"), std::string::npos)
        << error_reading(dir);
}

// Issue 43: what a hostile flight folder did before (a 10^9 s stamp sized a time grid past memory,
// a duplicate key or a dangling legs.csv was silently read, a body name that cannot read back was
// written, a CR-only file was echoed whole into the error) is one located line of at most 200
// characters, and a flight that cannot be written leaves no folder.
TEST(FlightFolder, HostileFilesAreRefusedInOneShortLocatedLine) {
    dw::test::TempDir d;
    const std::string dir = d.file("f");
    auto fresh = [&] { write_flight(sample_flight(), dir); };
    std::string bodies = "t,body,n,e,d,qw,qx,qy,qz\n0,sufferer,0,0,-1.4,1,0,0,0\n0,v1,0,0,-1.7,1,0,0,0\n";
    for (int i = 0; i < 300; ++i) bodies += "0.01,b" + std::to_string(i) + ",0,0,-1,1,0,0,0\n";
    const std::string meta = (fresh(), dw::read_file(dir + "/meta.json"));
    const struct {
        const char* file;
        std::string text, expect;
    } cases[] = {
        {"wrench.csv", many_rows(3) + "1e9,1,2,3,4,5,6\n", "fewer than one per 0.1 s: a stray stamp or a gap"},
        {"wrench.csv", std::string(375000, '\r'), "wrench.csv:1: header is '\\x0D\\x0D"},
        {"poses.csv", "t,body,n,e,d,qw,qx,qy,qz\n0,sufferer,0,0,-1.4,1,0,0,0\n0,v\"1,0,0,-1.7,1,0,0,0\n",
         "poses.csv:3: column body: 'v\"1' holds a comma, a double quote or a control byte"},
        {"poses.csv", "t,body,n,e,d,qw,qx,qy,qz\n0,sufferer,0,0,-1.4,1,0,0,0\n0,v\xff,0,0,-1.7,1,0,0,0\n",
         "poses.csv:3: column body: 'v\\xFF' is not UTF-8"},
        {"poses.csv", bodies, "column body: a flight holds at most 256 bodies"},
        {"meta.json", "{\"format\": \"downwash-flight/1\", \"format\": \"downwash-flight/1\"}",
         "meta.json: field 'format': given twice"},
        {"meta.json",
         meta.substr(0, meta.find("\"single\"")) + "\"" + std::string(1 << 20, 'x') + "\"" +
             meta.substr(meta.find("\"single\"") + 8),
         "field 'formation': 'xxxxxxxx"},
        {"meta.json",
         meta.substr(0, meta.find("\"sufferer\": \"sufferer\"")) + "\"sufferer\": \"a\\nb\"" +
             meta.substr(meta.find("\"sufferer\": \"sufferer\"") + 22),
         "field 'sufferer': a body name: 'a\\x0Ab' holds"},
    };
    for (const auto& c : cases) {
        fresh();
        write(dir + "/" + c.file, c.text);
        const std::string e = error_reading(dir);
        EXPECT_NE(e.find(c.expect), std::string::npos) << c.file << ": " << e.substr(0, 300);
        EXPECT_LE(e.size(), 200u) << e.substr(0, 300);
        EXPECT_EQ(e.find('\n'), std::string::npos) << e.substr(0, 300);
    }
    fresh();
    std::filesystem::remove(dir + "/legs.csv");
    std::filesystem::create_symlink("nowhere.csv", dir + "/legs.csv");
    EXPECT_NE(error_reading(dir).find("legs.csv: a symbolic link to no file"), std::string::npos) << error_reading(dir);
    std::filesystem::remove(dir + "/legs.csv");
    std::filesystem::create_symlink("legs.csv", dir + "/legs.csv");
    EXPECT_NE(error_reading(dir).find("legs.csv: cannot read: Too many levels of symbolic links"), std::string::npos)
        << error_reading(dir);

    for (const std::string name : std::vector<std::string>{"a,b", "a\rb", "a\nb", "v\xff"}) {
        Flight f = sample_flight();
        f.bodies[1] = name;
        f.meta.neighbours = {name};
        f.meta.vehicles = {{name, VehicleInfo{}}};
        const std::string out = d.file("refused");
        EXPECT_THROW(write_flight(f, out), dw::InputError) << name;
        EXPECT_FALSE(std::filesystem::exists(out)) << "a refused flight left its folder behind";
    }
}

// Issue 43: a multi-file output whole or not at all. A folder staged and given up leaves nothing
// (and never touches what was in the folder before); a flight whose last file cannot be written
// (here a file-size limit, as a full disk would) leaves no folder, where wrench.csv, poses.csv and
// meta.json used to stay without it.
TEST(StagedFolder, AnOutputAppearsWholeOrNotAtAll) {
    namespace fs = std::filesystem;
    dw::test::TempDir d;
    {
        dw::StagedFolder out(d.file("new"));
        write(out.path() + "/a.txt", "a");
    }
    EXPECT_FALSE(fs::exists(d.file("new")));
    fs::create_directories(d.file("old"));
    write(d.file("old/mine.txt"), "the user's");
    {
        dw::StagedFolder out(d.file("old"));
        fs::create_directories(out.path() + "/figures");
        write(out.path() + "/figures/b.png", "b");
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(d.file("old")), fs::directory_iterator()), 1);
    {
        dw::StagedFolder out(d.file("old"));
        fs::create_directories(out.path() + "/figures");
        write(out.path() + "/figures/b.png", "b");
        out.commit();
    }
    EXPECT_EQ(dw::read_file(d.file("old/figures/b.png")), "b");
    EXPECT_EQ(dw::read_file(d.file("old/mine.txt")), "the user's");
    EXPECT_EQ(std::distance(fs::directory_iterator(d.file("old")), fs::directory_iterator()), 2);

    Flight f = sample_flight();
    f.meta.reference = ReferenceInfo{"a model", {"f_d"}};
    for (int i = 0; i < 3000; ++i) f.reference.push_back({0.001 * i, {NAN, NAN, 1.25, NAN, NAN, NAN}});
    rlimit old{};
    ::getrlimit(RLIMIT_FSIZE, &old);
    const auto previous = std::signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG instead
    rlimit small = old;
    small.rlim_cur = 16 << 10;  // wrench.csv, poses.csv and meta.json fit; reference.csv (~40 KB) does not
    ::setrlimit(RLIMIT_FSIZE, &small);
    EXPECT_THROW(write_flight(f, d.file("flight")), dw::RuntimeError);
    ::setrlimit(RLIMIT_FSIZE, &old);
    std::signal(SIGXFSZ, previous);
    EXPECT_FALSE(fs::exists(d.file("flight")));
    write_flight(f, d.file("flight"));  // and without the limit it is written whole
    EXPECT_EQ(read_flight(d.file("flight")).reference.size(), 3000u);
}
