#include "lab/keys.hpp"

#include <chrono>
#include <ostream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/roles.hpp"
#include "lab/labfile.hpp"
#include "security/keystore.hpp"

namespace dw::lab {

namespace {

// Each process of the lab file as the role its executable plays; the launcher and an operator.
std::vector<security::IdentityRequest> identities_of(const LabFile& lab) {
    std::vector<security::IdentityRequest> v;
    for (const auto& p : lab.processes) {
        const auto role = dds::role_of_executable(p.run.front());
        if (!role)
            throw InputError(log::cat(lab.path, ": process ", p.name, ": '", p.run.front(),
                                      "' plays no lab role (expected a lab executable)"));
        v.push_back({p.name, *role});
    }
    for (dds::Role r : {dds::Role::launcher, dds::Role::operator_}) v.push_back({std::string(dds::role_name(r)), r});
    return v;
}

long days_left(std::chrono::system_clock::time_point t) {
    return std::chrono::duration_cast<std::chrono::hours>(t - std::chrono::system_clock::now()).count() / 24;
}

}  // namespace

int keys_create(const KeysOptions& o, std::ostream& out) {
    security::KeystoreOptions k;
    k.dir = o.keystore;
    k.days = o.days;
    k.identities = o.lab_path.empty() ? security::role_identities() : identities_of(load_lab(o.lab_path));
    const auto r = security::create_keystore(k);
    if (r.new_ca)
        out << "created the lab CA in " << o.keystore
            << "/ca.cert.pem (its key: private/ca.key.pem, keep it off the lab machines)\n";
    for (const auto& n : r.created) out << "created identity " << n << "\n";
    for (const auto& n : r.kept) out << "kept identity " << n << " (already there)\n";
    if (r.refreshed_governance) out << "signed the governance again: the lab's topics changed\n";
    for (const auto& n : r.refreshed) out << "signed the permissions of " << n << " again: its role's topics changed\n";
    return 0;
}

int keys_list(const std::string& keystore, std::ostream& out) {
    const auto l = security::list_keystore(keystore);
    out << "CA expires in " << days_left(l.ca_not_after) << " days\n";
    for (const auto& i : l.identities)
        out << i.name << "  " << i.subject << "  expires in " << days_left(i.not_after) << " days"
            << (i.verifies ? "" : "  NOT SIGNED BY THIS KEYSTORE'S CA") << "\n";
    for (const auto& i : l.identities)
        if (!i.verifies)
            throw InputError(log::cat(keystore, "/identities/", i.name,
                                      ": certificate or permissions not signed by this keystore's CA"));
    return 0;
}

}  // namespace dw::lab
