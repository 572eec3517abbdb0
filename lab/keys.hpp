#pragma once
// `dw-lab keys`: the lab's DDS Security keystore — made from a lab file (one identity per
// process, its role from its executable, plus the launcher and an operator) and listed with what
// expires when.
#include <iosfwd>
#include <string>

namespace dw::lab {

struct KeysOptions {
    std::string keystore;
    std::string lab_path;  // "" : one identity per role
    int days = 365;
};

// Prints what was created and kept; returns the exit code.
int keys_create(const KeysOptions& o, std::ostream& out);
int keys_list(const std::string& keystore, std::ostream& out);

}  // namespace dw::lab
