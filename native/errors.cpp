// How the shim reports a failure of the core (declared in shim.h).
#include "shim.h"

namespace mcdem_shim {

std::string last_mcdem_error() {
    char buf[512];
    mcdem_last_error(buf, sizeof(buf));
    return std::string(buf);
}

void stop_at_contact(LAMMPS *lmp, int i, int j, const std::string &why) {
    char who[64];
    if (j < 0)
        std::snprintf(who, sizeof(who), "particle %d at a wall", lmp->atom->tag[i]);
    else
        std::snprintf(who, sizeof(who), "particles %d and %d", lmp->atom->tag[i], lmp->atom->tag[j]);
    char msg[800];
    std::snprintf(msg, sizeof(msg), "model mc_advanced: %s, step " BIGINT_FORMAT ": %s", who,
                  lmp->update->ntimestep, why.c_str());
    lmp->error->one(FLERR, msg);
}

}  // namespace mcdem_shim
