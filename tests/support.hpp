#pragma once
// Helpers for tests that start the lab's executables as separate processes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/files.hpp"
#include "core/subprocess.hpp"

namespace dw::test {

// Where the lab's executables were built.
inline std::string bin(const std::string& name) { return std::string(DW_BIN_DIR) + "/" + name; }

// The domain ids tests take, and where a test process marks the one it holds.
inline constexpr int kFirstTestDomain = 100, kTestDomains = 120;
inline constexpr const char* kTestDomainLocks = "/tmp/dw-test-domains";

// A domain id of this test process's own, so tests run in parallel do not hear each other: the
// first free one from a start the process id picks, held by a lock on a file named after it (the
// kernel drops the lock when the process ends, however it ends). Taken as "100 + pid % 120" it was
// shared by two running tests now and then, which then discovered each other's participants.
// Every free id held: the pid's own (as before).
inline int claim_test_domain() {
    const int start = static_cast<int>(::getpid() % kTestDomains);
    if (::mkdir(kTestDomainLocks, 01777) == 0) ::chmod(kTestDomainLocks, 01777);  // every user's tests (umask aside)
    for (int i = 0; i < kTestDomains; ++i) {
        const int d = kFirstTestDomain + (start + i) % kTestDomains;
        const std::string file = std::string(kTestDomainLocks) + "/" + std::to_string(d);
        const int fd = ::open(file.c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0444);  // flock needs no write access
        if (fd < 0) continue;
        if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return d;  // fd left open: the lock lasts the process
        ::close(fd);
    }
    return kFirstTestDomain + start;
}
inline int test_domain() {
    static const int domain = claim_test_domain();  // one per process
    return domain;
}

// A fresh temporary directory, removed with the object (kept, and named on stderr, when the
// environment sets DW_TEST_KEEP: to read a test's files after it ran).
class TempDir {
public:
    TempDir() {
        std::string pattern = (std::filesystem::temp_directory_path() / "dwtest-XXXXXX").string();
        path_ = ::mkdtemp(pattern.data());
    }
    ~TempDir() {
        if (std::getenv("DW_TEST_KEEP")) {
            std::fprintf(stderr, "kept %s (DW_TEST_KEEP)\n", path_.c_str());
            return;
        }
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }

private:
    std::filesystem::path path_;
};

struct RunResult {
    int status = -1;
    std::string out;
    std::string err;
};

// Runs a command to completion (killed after `limit`, a safety net, not a performance bound).
// env: extra NAME=VALUE entries.
inline RunResult run(const std::vector<std::string>& argv, const TempDir& dir,
                     std::chrono::milliseconds limit = std::chrono::milliseconds(120000),
                     const std::vector<std::string>& env = {}) {
    static int counter = 0;
    const std::string tag = std::to_string(counter++);
    Subprocess p({argv, dir.file("out" + tag), dir.file("err" + tag), env});
    auto status = p.wait_for(limit);
    RunResult r;
    r.status = status ? *status : p.stop();
    r.out = read_file(dir.file("out" + tag));
    r.err = read_file(dir.file("err" + tag));
    return r;
}

inline std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::size_t start = 0;
    while (start < text.size()) {
        const auto end = text.find('\n', start);
        out.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return out;
}

// Bad input: exit 2 and exactly one line on stderr containing `needle`.
inline void expect_one_line_exit_2(const RunResult& r, const std::string& needle) {
    EXPECT_EQ(r.status, 2) << r.err;
    const auto l = lines(r.err);
    ASSERT_EQ(l.size(), 1u) << r.err;
    EXPECT_NE(l[0].find(needle), std::string::npos) << l[0];
}

// The nominal stand under 12 known loads, as dw-stand-agent calibrate reads them: tared counts =
// cell forces x 21400, the minimum-norm cell forces of the nominal geometry (vertical cells at
// 45° + k 90°).
inline std::string known_loads_csv() {
    std::string csv = "c0,c1,c2,c3,c4,c5,c6,c7,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n";
    const double r = 0.1;
    for (int i = 0; i < 12; ++i) {
        const double fz = 1.0 + i, fn = (i % 3) - 1.0, fe = (i % 4) - 1.5, mr = 0.01 * (i % 5), mp = -0.01 * (i % 3),
                     my = 0.005 * (i % 2);
        double v[4];
        for (int k = 0; k < 4; ++k) {
            const double phi = M_PI / 4 + M_PI / 2 * k, x = r * std::cos(phi), y = r * std::sin(phi);
            v[k] = fz / 4 + mr * y / (4 * r * r * 0.5) - mp * x / (4 * r * r * 0.5);
        }
        const double n4 = fn / 2 - my / (4 * r), n5 = fn / 2 + my / (4 * r);
        const double e6 = fe / 2 - my / (4 * r), e7 = fe / 2 + my / (4 * r);
        char line[512];
        std::snprintf(line, sizeof(line), "%f,%f,%f,%f,%f,%f,%f,%f,%f,%f,%f,%f,%f,%f\n", v[0] * 21400, v[1] * 21400,
                      v[2] * 21400, v[3] * 21400, n4 * 21400, n5 * 21400, e6 * 21400, e7 * 21400, fn, fe, fz, mr, mp,
                      my);
        csv += line;
    }
    return csv;
}

}  // namespace dw::test
