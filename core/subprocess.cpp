#include "core/subprocess.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <thread>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"

extern char** environ;

namespace dw {
namespace {
int decode_status(int raw) {
    if (WIFEXITED(raw)) return WEXITSTATUS(raw);
    if (WIFSIGNALED(raw)) return 128 + WTERMSIG(raw);
    return -1;
}
}  // namespace

Subprocess::Subprocess(const SpawnOptions& options) {
    if (options.argv.empty()) throw RuntimeError("spawn: empty command line");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!options.stdout_path.empty()) {
        posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, options.stdout_path.c_str(),
                                         O_WRONLY | O_CREAT | O_TRUNC | O_APPEND, 0644);
    }
    if (!options.stderr_path.empty()) {
        if (options.stderr_path == options.stdout_path) {
            posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
        } else {
            posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, options.stderr_path.c_str(),
                                             O_WRONLY | O_CREAT | O_TRUNC | O_APPEND, 0644);
        }
    }
    // The parent may block SIGINT/SIGTERM (dw::Shutdown); children start with a clean mask.
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t empty;
    sigemptyset(&empty);
    posix_spawnattr_setsigmask(&attr, &empty);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);

    std::vector<std::string> env_strings;
    for (char** e = environ; *e != nullptr; ++e) env_strings.emplace_back(*e);
    for (const auto& extra : options.env) env_strings.push_back(extra);
    std::vector<char*> envp;
    for (auto& e : env_strings) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::vector<std::string> args = options.argv;
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);

    const int rc = posix_spawnp(&pid_, argv[0], &actions, &attr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    if (rc != 0) {
        pid_ = -1;
        throw RuntimeError("cannot start '" + options.argv[0] + "': " + std::strerror(rc));
    }
    if (options.niceness != 0) {
        errno = 0;
        const int now = ::getpriority(PRIO_PROCESS, static_cast<id_t>(pid_));
        if (errno == 0) ::setpriority(PRIO_PROCESS, static_cast<id_t>(pid_), now + options.niceness);
    }
}

Subprocess::Subprocess(Subprocess&& other) noexcept : pid_(other.pid_), status_(other.status_) { other.pid_ = -1; }

Subprocess::~Subprocess() {
    if (pid_ > 0 && !status_) {
        ::kill(pid_, SIGKILL);
        int raw = 0;
        ::waitpid(pid_, &raw, 0);
    }
}

void Subprocess::signal(int sig) const {
    if (pid_ > 0 && !status_) ::kill(pid_, sig);
}

std::optional<int> Subprocess::poll() {
    if (status_ || pid_ <= 0) return status_;
    int raw = 0;
    const pid_t r = ::waitpid(pid_, &raw, WNOHANG);
    if (r == pid_) status_ = decode_status(raw);
    return status_;
}

std::optional<int> Subprocess::wait_for(std::chrono::milliseconds d) {
    const auto deadline = std::chrono::steady_clock::now() + d;
    while (!poll()) {
        if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return status_;
}

bool Subprocess::running() { return !poll(); }

int Subprocess::stop(std::chrono::milliseconds grace) {
    signal(SIGTERM);
    if (auto s = wait_for(grace)) return *s;
    signal(SIGKILL);
    return wait_for(std::chrono::milliseconds(5000)).value_or(-1);
}

std::string executable_dir() {
    char buf[4096];
    const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof(buf) - 1);
    if (n <= 0) return ".";
    std::string path(buf, static_cast<std::size_t>(n));
    return path.substr(0, path.find_last_of('/'));
}

namespace {
// At most this many characters of a child's last line are carried into an error.
constexpr std::size_t kChildLineChars = 240;

// The last non-empty line of `text`, control bytes dropped, cut to kChildLineChars.
std::string last_line(std::string_view text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.remove_suffix(1);
    const auto nl = text.find_last_of("\r\n");
    if (nl != std::string_view::npos) text.remove_prefix(nl + 1);
    std::string line;
    for (const char ch : text)
        if (static_cast<unsigned char>(ch) >= 0x20) line += ch;
    if (line.size() > kChildLineChars) line = line.substr(0, kChildLineChars) + "...";
    return line;
}
constexpr std::streamoff kTailBytes = 4096;  // where a log's last line is looked for
}  // namespace

std::string last_line_of(const std::string& file) {
    std::ifstream in(file, std::ios::binary | std::ios::ate);
    if (!in) return "";
    const std::streamoff size = in.tellg();
    in.seekg(std::max<std::streamoff>(0, size - kTailBytes));
    std::string tail(static_cast<std::size_t>(std::min(size, kTailBytes)), '\0');
    in.read(tail.data(), static_cast<std::streamsize>(tail.size()));
    tail.resize(static_cast<std::size_t>(in.gcount()));
    return last_line(tail);
}

namespace {
SpawnOptions sibling_options(const std::vector<std::string>& args, const std::string& log_file, int niceness) {
    std::vector<std::string> argv{executable_dir() + "/" + args.at(0)};
    argv.insert(argv.end(), args.begin() + 1, args.end());
    return {argv, log_file, log_file, {}, niceness};
}
}  // namespace

Sibling::Sibling(const std::vector<std::string>& args, const std::string& log_file, int niceness,
                 const std::stop_token& stop)
    : name_(args.at(0)), log_file_(log_file), p_(sibling_options(args, log_file, niceness)) {
    on_stop_.emplace(stop, [this] { ask_to_stop(); });
}

void Sibling::ask_to_stop() {
    const std::lock_guard lock(m_);
    if (!asked_ && p_.running()) p_.signal(SIGTERM);
    asked_ = true;
}

Sibling::~Sibling() {
    on_stop_.reset();  // waits for a callback under way
    ask_to_stop();
    p_.wait_for(kSiblingStopGrace);  // still running then: ~Subprocess kills it
}

bool Sibling::running() {
    const std::lock_guard lock(m_);
    return p_.running();
}

void Sibling::finish(const std::stop_token& stop) {
    std::optional<int> st;
    while (true) {
        {
            const std::lock_guard lock(m_);
            st = p_.wait_for(std::chrono::milliseconds(200));
        }
        // Stopped, it was asked to stop (and ends as asked); the destructor waits for it.
        if (stop.stop_requested()) throw Stopped(log::cat("stopped during ", name_));
        if (st) break;
    }
    if (*st != 0) {
        const std::string said = last_line_of(log_file_);
        throw RuntimeError(log::cat(name_, " failed (status ", *st, ")", said.empty() ? "" : ": ", said));
    }
}

void run_sibling(const std::vector<std::string>& args, const std::string& log_file, const std::stop_token& stop) {
    Sibling(args, log_file).finish(stop);
}

}  // namespace dw
