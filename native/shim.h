/*
 * Shared by the files of the LIGGGHTS 3.8 shim for `pair_style gran model mc_advanced` (advanced
 * multi-contact model, Ghods et al. 2022). Every formula lives in the Rust core behind
 * native/mcdem.h; the shim only moves data between LIGGGHTS's data structures and that C ABI:
 *
 *  - settings.h: the model's keywords with named options or strictly parsed numbers;
 *  - normal_model.h, normal_model_setup.cpp: NormalModel<MC_ADVANCED>, the normal force of one
 *    contact (mcdem_hertz_normal on the overlap of the multi-contact-modified radii) and the
 *    per-contact record (contact surface and |F_n| of this step) that the next step's radius
 *    changes need; its settings, materials and wall checks;
 *  - bookkeeping.cpp: the multi-contact bookkeeping, run by the pair's model at the start of each
 *    force pass: gathers every contact of each owned particle (pairs and walls), calls
 *    mcdem_radius_changes (Eq. 2 with the Eq. 3 cap) and stores the radius change per contact
 *    where LIGGGHTS's pair and wall loops read it when `store multicontact data` is switched on.
 *    That storage, and the detection of contacts with the grown radii, is the library's own
 *    machinery for its standard multi-contact model, so both models share the same contact
 *    detection and communication;
 *  - pair_loop.h, pair_loop.cpp, pair_batch.h, pair_batch.cpp: the model's own pair loop, which
 *    hands overlapping pairs to the core eight at a time (mcdem_pair_batch_evaluate: normal and
 *    tangential force together, the code `mcdem run` uses) and keeps the one-contact path for
 *    settings and outputs the batch does not compute;
 *  - registration.cpp: the model name and the optimised template instances on the pair and wall
 *    factories, and the entry point of the `mcdem-liggghts` executable;
 *  - errors.cpp: how a contact the core refuses stops the run.
 */
#ifndef MCDEM_SHIM_H
#define MCDEM_SHIM_H

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "properties.h"
#include "update.h"
// Must precede pair_gran_base.h: the installed fix_insert_stream_predefined.h does not include its base.
#include "fix_insert_stream.h"
#include "contact_models.h"
#include "fix_contact_property_atom.h"
#include "fix_contact_history_mesh.h"
#include "fix_contact_property_atom_wall.h"
#include "fix_mesh_surface.h"
#include "fix_multicontact_halfspace.h"
#include "fix_neighlist_mesh.h"
#include "fix_property_atom.h"
#include "fix_property_global.h"
#include "fix_wall_gran.h"
#include "fix_wall_gran_base.h"
#include "granular_pair_style.h"
#include "granular_wall.h"
#include "pair_gran.h"
#include "pair_gran_base.h"
#include "pair_gran_proxy.h"

#include "mcdem.h"

#ifndef MCDEM_MC_ADVANCED_ID
#error "MCDEM_MC_ADVANCED_ID must be defined by the build (an id unused by the installed LIGGGHTS)"
#endif

namespace LIGGGHTS {
namespace ContactModels {
static const int MC_ADVANCED = MCDEM_MC_ADVANCED_ID;
}
}  // namespace LIGGGHTS

namespace mcdem_shim {

using namespace LAMMPS_NS;
using namespace LIGGGHTS;
using namespace LIGGGHTS::ContactModels;

// --- access to private members of the library's classes ---------------------------------------
// The standard explicit-instantiation idiom: a Tag names a member's type and declares
// private_member(Tag); `template struct PrivateAccess<Tag, &Class::member>;`, written once in the
// one file that reads the member, defines it. The compiler checks the member's name and type.
// Tags must live in this namespace (the friend defined here is the one the Tag declares).
template <typename Tag, typename Tag::type Member>
struct PrivateAccess {
    friend typename Tag::type private_member(Tag) { return Member; }
};

// Offset of the per-contact record in a contact history. LIGGGHTS's HistoryData scales the offset
// of wall histories by sizeof(double), so the record must sit first (offset 0) in wall histories.
const char *const kRecordName = "mcdem_mc_record";

// How far (as a multiple of the radius sum) a pair is still tracked as "close": a contact that
// only radius growth creates must be known before it touches. Users can raise it with
// `neigh_modify contact_distance_factor`.
const double kContactDistanceFactor = 1.2;

// A pair's record (after its two radii and |F_n|): the radius changes of the partner with the
// smaller and with the larger atom ID at this contact.
const int kPairDrLo = 3;
const int kPairDrHi = 4;

// The core's message of its last failure on this thread (errors.cpp).
std::string last_mcdem_error();

// Stops the run at a contact the model cannot integrate: one ERROR line naming the particles
// (j < 0: particle i at a wall), the step and the core's reason. Both pair paths and the walls
// report through here.
void stop_at_contact(LAMMPS *lmp, int i, int j, const std::string &why);

}  // namespace mcdem_shim

// The shim's files name the library's classes and the shim's helpers unqualified.
using namespace mcdem_shim;

#endif
