#include "core/files.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw {
namespace fs = std::filesystem;

fs::file_status input_status(const std::string& path, std::string_view what) {
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (ec && ec != std::errc::no_such_file_or_directory)  // a symbolic link loop, a path through a file
        throw InputError(log::cat(what, " ", path, ": cannot read: ", ec.message()));
    return status;
}

void require_readable_file(const std::string& path, std::string_view what) {
    if (path.empty()) throw InputError(log::cat(what, ": no file given"));
    const auto status = input_status(path, what);
    std::error_code ec;
    if (!fs::exists(status)) {
        const bool dangling = fs::is_symlink(fs::symlink_status(path, ec));
        throw InputError(log::cat(what, " ", path, dangling ? ": a symbolic link to no file" : ": no such file"));
    }
    if (fs::is_directory(status)) throw InputError(log::cat(what, " ", path, ": is a directory, expected a file"));
    if (!fs::is_regular_file(status)) throw InputError(log::cat(what, " ", path, ": not a regular file"));
    if (::access(path.c_str(), R_OK) != 0) {
        throw InputError(log::cat(what, " ", path, ": cannot read: ", std::strerror(errno)));
    }
}

std::string read_file(const std::string& path, std::string_view what) {
    require_readable_file(path, what);
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    if (in) out << in.rdbuf();
    if (!in || in.bad()) throw InputError(log::cat(what, " ", path, ": cannot read the file"));
    return out.str();
}

std::string read_file(const std::string& path) {
    try {
        return read_file(path, "file");
    } catch (const InputError& e) {
        throw RuntimeError(e.what());
    }
}

bool present(const std::string& path) {
    std::error_code ec;
    const auto type = fs::symlink_status(path, ec).type();
    if (ec) return ec != std::errc::no_such_file_or_directory;  // another error (permissions): the read says it
    return type != fs::file_type::not_found;
}

namespace {
// A folder that exists but refuses writing (read-only file system, permissions) is the machine's
// state, not a mistake in the command: a runtime failure (exit 1), as a full disk is.
void require_write_access(const fs::path& dir, const std::string& path, std::string_view what) {
    if (::access(dir.c_str(), W_OK) != 0)
        throw RuntimeError(log::cat(what, " ", path, ": cannot write in ", dir.string(), ": ", std::strerror(errno)));
}
}  // namespace

void require_replaceable(const std::string& path, std::string_view what) {
    std::error_code ec;
    const char* kind = nullptr;
    switch (fs::symlink_status(path, ec).type()) {
        case fs::file_type::fifo: kind = "a FIFO"; break;
        case fs::file_type::character:
        case fs::file_type::block: kind = "a device node"; break;
        case fs::file_type::socket: kind = "a socket"; break;
        default: return;
    }
    throw InputError(log::cat(what, " ", path, ": is ", kind, "; an output replaces only a regular file"));
}

void require_writable_path(const std::string& path, std::string_view what) {
    if (path.empty()) throw InputError(log::cat(what, ": no path given"));
    require_replaceable(path, what);
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw InputError(log::cat(what, " ", path, ": is a directory, expected a file name"));
    const fs::path dir = fs::absolute(fs::path(path), ec).parent_path();
    if (!fs::exists(dir, ec))
        throw InputError(log::cat(what, " ", path, ": the folder ", dir.string(), " does not exist"));
    if (!fs::is_directory(dir, ec))
        throw InputError(log::cat(what, " ", path, ": ", dir.string(), " is not a directory"));
    require_write_access(dir, path, what);
}

void require_output_dir(const std::string& path, std::string_view what) {
    if (path.empty()) throw InputError(log::cat(what, ": no folder given"));
    std::error_code ec;
    if (fs::exists(path, ec) && !fs::is_directory(path, ec))
        throw InputError(log::cat(what, " ", path, ": is a file, expected a folder"));
    fs::path dir = fs::absolute(fs::path(path), ec);
    while (!fs::exists(dir, ec) && dir.has_parent_path() && dir != dir.parent_path()) dir = dir.parent_path();
    if (!fs::is_directory(dir, ec))
        throw InputError(log::cat(what, " ", path, ": ", dir.string(), " is not a directory"));
    require_write_access(dir, path, what);
}

AtomicFile::AtomicFile(std::string path, unsigned mode)
    : path_(std::move(path)), tmp_(log::cat(path_, ".tmp-", ::getpid())) {
    require_replaceable(path_, "output");
    const fs::path parent = fs::path(path_).parent_path();
    std::error_code ec;
    if (!parent.empty() && !fs::exists(parent, ec) && !fs::create_directories(parent, ec)) {
        throw RuntimeError(log::cat("cannot write ", path_, ": cannot create ", parent.string(), ": ", ec.message()));
    }
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, static_cast<mode_t>(mode));
    if (fd_ < 0) throw RuntimeError(log::cat("cannot write ", path_, ": ", std::strerror(errno)));
    buffer_.reserve(kBlock);
}

AtomicFile::~AtomicFile() {
    if (fd_ < 0) return;
    ::close(fd_);
    ::unlink(tmp_.c_str());
}

void AtomicFile::fail(int err) {
    ::close(fd_);
    fd_ = -1;
    ::unlink(tmp_.c_str());
    throw RuntimeError(log::cat("cannot write ", path_, ": ", std::strerror(err)));
}

void AtomicFile::flush() {
    write_through(buffer_);
    buffer_.clear();
}

void AtomicFile::write_through(std::string_view bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) fail(n < 0 ? errno : ENOSPC);
        done += static_cast<std::size_t>(n);
    }
}

void AtomicFile::write(std::string_view bytes) {
    if (fd_ < 0) throw RuntimeError(log::cat("cannot write ", path_, ": already closed"));
    if (buffer_.size() + bytes.size() > kBlock) flush();
    if (bytes.size() >= kBlock) {
        write_through(bytes);  // already a large block: not copied into the buffer first
    } else {
        buffer_.append(bytes);
    }
}

void AtomicFile::commit() {
    if (fd_ < 0) throw RuntimeError(log::cat("cannot write ", path_, ": already closed"));
    flush();
    const int fd = fd_;
    fd_ = -1;
    int err = ::close(fd) != 0 ? errno : 0;
    if (err == 0 && ::rename(tmp_.c_str(), path_.c_str()) != 0) err = errno;
    if (err != 0) {
        ::unlink(tmp_.c_str());
        throw RuntimeError(log::cat("cannot write ", path_, ": ", std::strerror(err)));
    }
}

StagedFolder::StagedFolder(const std::string& dir) : dir_(dir) {
    std::error_code ec;
    made_dir_ = !fs::exists(dir_, ec);
    // The highest folder this makes: a failure removes what it made, parents included.
    for (fs::path p = fs::absolute(dir_, ec); made_dir_ && !p.empty() && !fs::exists(p, ec) && p != p.parent_path();
         p = p.parent_path())
        made_top_ = p.string();
    staging_ = (fs::path(dir_) / log::cat(".staging-", ::getpid())).string();
    fs::remove_all(staging_, ec);  // a staging folder of a killed process with this pid
    if (!fs::create_directories(staging_, ec) || ec)
        throw RuntimeError(log::cat("cannot write ", dir_, ": ", ec ? ec.message() : "cannot create a folder in it"));
}

StagedFolder::~StagedFolder() {
    std::error_code ec;
    fs::remove_all(staging_, ec);
    if (committed_ || !made_dir_) return;
    for (fs::path p = fs::absolute(dir_, ec); !p.empty(); p = p.parent_path()) {
        if (!fs::remove(p, ec)) break;  // only if empty: nothing else was put there
        if (p.string() == made_top_ || p == p.parent_path()) break;
    }
}

void StagedFolder::commit() {
    std::error_code ec;
    std::vector<fs::path> files;
    for (auto it = fs::recursive_directory_iterator(staging_, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec)) {
        const fs::path to = fs::path(dir_) / fs::relative(it->path(), staging_);
        if (it->is_directory()) fs::create_directories(to, ec);
        else files.push_back(it->path());
        if (ec) break;
    }
    for (std::size_t i = 0; !ec && i < files.size(); ++i)
        fs::rename(files[i], fs::path(dir_) / fs::relative(files[i], staging_), ec);
    if (ec) throw RuntimeError(log::cat("cannot write ", dir_, ": ", ec.message()));
    committed_ = true;
    fs::remove_all(staging_, ec);
}

void write_file(const std::string& path, std::string_view content, unsigned mode) {
    AtomicFile f(path, mode);
    f.write(content);
    f.commit();
}

bool is_plain_name(std::string_view name) {
    if (name.empty() || name.front() == '.') return false;
    return std::all_of(name.begin(), name.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
    });
}

}  // namespace dw
