#include "importer/importer.hpp"

#include "importer/neural_swarm.hpp"

namespace dw::importer {

const std::vector<const Importer*>& importers() {
    static const std::vector<const Importer*> all = {&neural_swarm_importer()};
    return all;
}

}  // namespace dw::importer
