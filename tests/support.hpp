#pragma once
// Helpers for tests that start the lab's executables as separate processes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
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

}  // namespace dw::test
