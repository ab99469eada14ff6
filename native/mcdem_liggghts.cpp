/*
 * LIGGGHTS plumbing for `pair_style gran model mc_advanced` (advanced multi-contact model,
 * Ghods et al. 2022). Every formula lives in the Rust core behind native/mcdem.h; this file only
 * moves data between LIGGGHTS's data structures and that C ABI:
 *
 *  - NormalModel<MC_ADVANCED>: the normal force of one contact, computed by mcdem_hertz_normal
 *    on the overlap of the multi-contact-modified radii, plus the per-contact record (contact
 *    surface and |F_n| of this step) that the next step's radius changes need.
 *  - mc_pair_loop and McBatch: the model's own pair loop, which hands overlapping pairs to the
 *    core eight at a time (mcdem_pair_batch_evaluate: normal and tangential force together, the
 *    code `mcdem run` uses) and keeps the one-contact path above for settings and outputs the
 *    batch does not compute.
 *  - The multi-contact bookkeeping, run by the pair's model at the start of each force pass:
 *    gathers every contact of each owned particle (pairs and walls), calls mcdem_radius_changes
 *    (Eq. 2 with the Eq. 3 cap) and stores the radius change per contact where LIGGGHTS's pair
 *    and wall loops read it when `store multicontact data` is switched on. That storage, and the
 *    detection of contacts with the grown radii, is the library's own machinery for its standard
 *    multi-contact model, so both models share the same contact detection and communication.
 *  - Registration of the model name and of the optimised template instances on the pair and
 *    wall factories, and the entry point of the `mcdem-liggghts` executable.
 */

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

namespace {

using namespace LAMMPS_NS;
using namespace LIGGGHTS;
using namespace LIGGGHTS::ContactModels;

// --- access to Settings' private table ------------------------------------------------------
// `mprTest abs|signed` is a keyword with named options, but Settings only offers on/off, yes/no
// and double keywords publicly. The standard explicit-instantiation idiom gives a pointer to the
// private table so that our own Setting subclass can be registered next to the library's ones.
template <typename Tag, typename Tag::type Member>
struct PrivateAccess {
    friend typename Tag::type private_member(Tag) { return Member; }
};
struct SettingsTableTag {
    typedef std::map<std::string, Setting *> Settings::*type;
    friend type private_member(SettingsTableTag);
};
template struct PrivateAccess<SettingsTableTag, &Settings::settings>;

// The same idiom for the per-atom row pointers of a contact store (FixContactHistory's protected
// partner_ and contacthistory_), which the multi-contact bookkeeping has to lay out itself for
// primitive walls (see McSource).
struct PartnerTag {
    typedef int **FixContactHistory::*type;
    friend type private_member(PartnerTag);
};
template struct PrivateAccess<PartnerTag, &FixContactHistory::partner_>;
struct RowsTag {
    typedef double **FixContactHistory::*type;
    friend type private_member(RowsTag);
};
template struct PrivateAccess<RowsTag, &FixContactHistory::contacthistory_>;

// A keyword with two named options (`mprTest abs|signed`, `pairRadii modified|stock`); `given`, if
// not NULL, records that the deck line gave it.
class ChoiceSetting : public Setting {
public:
    ChoiceSetting(const char *name, const char *off, const char *on, bool *target, bool *given)
        : Setting(name, 1), off_(off), on_(on), target_(target), given_(given) {}
    int parseArguments(char **args) {
        if (name != args[0]) return 0;
        const char *v = args[1];
        if (v && (off_ == v || on_ == v)) {
            *target_ = on_ == v;
            if (given_) *given_ = true;
            return 2;
        }
        error_message = "model mc_advanced: " + name + " must be '" + off_ + "' or '" + on_ + "', got '" +
                        (v ? v : "") + "'";
        return -1;
    }
    void print_value(FILE *out) { std::fprintf(out, "%s", (*target_ ? on_ : off_).c_str()); }

private:
    std::string off_, on_;
    bool *target_;
    bool *given_;
};

// Numeric model settings parsed strictly: the library's own DoubleSetting reads with atof, which
// would turn a typo into 0 without a word. Each parser takes the whole word or fails.
bool parse_nonnegative(const char *v, double *out) {
    char *end = NULL;
    const double d = std::strtod(v, &end);
    if (end == v || *end != '\0' || !std::isfinite(d) || d < 0.0) return false;
    *out = d;
    return true;
}

bool parse_step_count(const char *v, int *out) {
    char *end = NULL;
    const long k = std::strtol(v, &end, 10);
    if (end == v || *end != '\0' || k < 1 || k > 1000000000L) return false;
    *out = static_cast<int>(k);
    return true;
}

void print_setting(FILE *out, double v) { std::fprintf(out, "%g", v); }
void print_setting(FILE *out, int v) { std::fprintf(out, "%d", v); }

// `geometryTolerance 1e-3` (a number >= 0), `updateEvery 10` (a whole number of steps >= 1).
template <typename T, bool (*Parse)(const char *, T *)>
class StrictSetting : public Setting {
public:
    StrictSetting(const char *name, T *target, bool *given, const char *expected)
        : Setting(name, 1), target_(target), given_(given), expected_(expected) {}
    int parseArguments(char **args) {
        if (name != args[0]) return 0;
        const char *v = args[1];
        if (!v || !Parse(v, target_)) {
            error_message = "model mc_advanced: " + name + " must be " + expected_ + ", got '" + (v ? v : "") + "'";
            return -1;
        }
        *given_ = true;
        return 2;
    }
    void print_value(FILE *out) { print_setting(out, *target_); }

private:
    T *target_;
    bool *given_;
    std::string expected_;
};

std::string last_mcdem_error() {
    char buf[512];
    mcdem_last_error(buf, sizeof(buf));
    return std::string(buf);
}

// Stops the run at a contact the model cannot integrate: one ERROR line naming the particles
// (j < 0: particle i at a wall), the step and the core's reason. Both pair paths and the walls
// report through here.
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

// Offset of the per-contact record in a contact history. LIGGGHTS's HistoryData scales the offset
// of wall histories by sizeof(double), so the record must sit first (offset 0) in wall histories.
const char *const kRecordName = "mcdem_mc_record";

// How far (as a multiple of the radius sum) a pair is still tracked as "close": a contact that
// only radius growth creates must be known before it touches. Users can raise it with
// `neigh_modify contact_distance_factor`.
const double kContactDistanceFactor = 1.2;

// Model settings that only the pair style's model applies: it computes the radius changes of every
// contact, walls included. A wall may repeat them but not give other values (they would be ignored).
// pairRadii concerns pairs only (a wall contact always uses the modified radius): walls may give any.
enum SharedSetting { kMprTest, kGeometryTolerance, kUpdateEvery, kSharedSettings };

// A pair's record (after its two radii and |F_n|): the radius changes of the partner with the
// smaller and with the larger atom ID at this contact.
const int kPairDrLo = 3;
const int kPairDrHi = 4;

}  // namespace

namespace LIGGGHTS {
namespace ContactModels {

// Everything the multi-contact bookkeeping touches, gathered once per run.
//
// The library's per-atom stores size their rows when the neighbour lists are built, and the wall
// loops look a particle's radius change up in them without checking how many rows were filled
// this step; two consequences would make the results depend on when the lists were rebuilt:
//  - a primitive wall's store gives a particle its single row only if it was within half a skin
//    of the wall at the last build, while the wall records every contact within the contact
//    distance (and looks rows up by the particle's current position). A particle without a row
//    wrote into, and read from, the row of the next particle in the store's memory (a phantom
//    wall load on one of them);
//  - rows filled at an earlier step stay in the store until the next build, so a wall contact
//    that has been dropped since still finds its old radius change.
// Hence primitive walls get one row per particle that this bookkeeping owns (`own_partner`,
// `own_rows`), and every wall store's rows are emptied at each step before they are filled.
struct McSource {
    HistoryData history;
    FixContactPropertyAtom *store;
    bool wall;
    bool primitive;
    FixPropertyAtom *mesh_nneighs;  // mesh walls: the number of rows of each particle in the store
    std::vector<int> own_partner;
    std::vector<double> own_rows;
    McSource(const HistoryData &h, FixContactPropertyAtom *s, bool w, bool prim, FixPropertyAtom *nn)
        : history(h), store(s), wall(w), primitive(prim), mesh_nneighs(nn) {}
};

template <>
class NormalModel<MC_ADVANCED> : public NormalModelBase {
public:
    NormalModel(LAMMPS *lmp, IContactHistorySetup *hsetup, ContactModelBase *c)
        : NormalModelBase(lmp, hsetup, c),
          cmb_(c),
          record_offset_(-1),
          tangential_damping_(true),
          limit_force_(false),
          signed_test_(false),
          stock_pair_radii_(false),
          geometry_tolerance_(0.0),
          update_every_(1),
          last_update_(-1),
          cache_(NULL),
          ntypes_(0),
          sources_ready_(false) {
        for (int k = 0; k < kSharedSettings; k++) given_[k] = false;
        // Per-contact record read by the next step's radius changes: pairs the two modified radii
        // (see write_pair_record) and |F_n|; walls the contact point relative to the centre and
        // |F_n| (the layout LIGGGHTS's HistoryData expects).
        if (c->is_wall()) {
            record_offset_ = hsetup->add_history_value("mcdem_point_x", "0");
            hsetup->add_history_value("mcdem_point_y", "0");
            hsetup->add_history_value("mcdem_point_z", "0");
            hsetup->add_history_value("mcdem_fn", "0");
        } else {
            record_offset_ = hsetup->add_history_value("mcdem_radius_lo", "0");
            hsetup->add_history_value("mcdem_radius_hi", "0");
            hsetup->add_history_value("mcdem_fn", "0");
            // This step's radius changes of both partners at this contact (see copy_to_pair_records),
            // read by the pair loop (mc_pair_loop) without searching the per-atom store.
            hsetup->add_history_value("mcdem_dr_lo", "0");
            hsetup->add_history_value("mcdem_dr_hi", "0");
        }
        c->add_history_offset(kRecordName, record_offset_);
    }

    ~NormalModel() {
        std::map<LAMMPS *, NormalModel *>::iterator it = pair_models_.find(lmp);
        if (it != pair_models_.end() && it->second == this) pair_models_.erase(it);
        mcdem_influence_cache_free(cache_);
    }

    void registerSettings(Settings &settings) {
        settings.registerOnOff("tangential_damping", tangential_damping_, true);
        settings.registerOnOff("limitForce", limit_force_);
        std::map<std::string, Setting *> &table = settings.*private_member(SettingsTableTag());
        if (table.find("mprTest") == table.end())
            table["mprTest"] = new ChoiceSetting("mprTest", "abs", "signed", &signed_test_, &given_[kMprTest]);
        if (table.find("pairRadii") == table.end())
            table["pairRadii"] =
                new ChoiceSetting("pairRadii", "modified", "stock", &stock_pair_radii_, NULL);
        if (table.find("geometryTolerance") == table.end())
            table["geometryTolerance"] = new StrictSetting<double, parse_nonnegative>(
                "geometryTolerance", &geometry_tolerance_, &given_[kGeometryTolerance],
                "a finite number >= 0 (a fraction of the particle radius)");
        if (table.find("updateEvery") == table.end())
            table["updateEvery"] =
                new StrictSetting<int, parse_step_count>("updateEvery", &update_every_, &given_[kUpdateEvery],
                                                        "a whole number of steps from 1 to 1000000000");
    }

    void postSettings(IContactHistorySetup *, ContactModelBase *) {
        if (cmb_->is_wall()) return;
        pair_models_[lmp] = this;
        // Switches on the library's per-contact radius storage, read by the pair and wall loops
        // for detection, overlap and effective radius; it must be set before the pair's init.
        PairGran *pg = dynamic_cast<PairGran *>(force->pair);
        if (!pg) error->all(FLERR, "model mc_advanced: the pair style is not a granular pair style");
        pg->do_store_multicontact_data();
    }

    void connectToProperties(PropertyRegistry &) {
        read_materials();
        if (cmb_->is_wall()) {
            PairGran *pg = static_cast<PairGran *>(force->pair_match("gran", 0));
            if (!pg || !pg->contact_match("normal", "mc_advanced"))
                error->all(FLERR, "fix wall/gran with model mc_advanced needs `pair_style gran model mc_advanced`: "
                                  "the multi-contact radius changes are computed by the pair style");
            check_wall_settings();
            return;
        }
        if (force->newton_pair)
            error->all(FLERR, "model mc_advanced needs `newton off` (per-contact data are stored on both partners)");
        neighbor->register_contact_dist_factor(kContactDistanceFactor);
        if (mcdem_pair_batch_size() != sizeof(mcdem_pair_batch))
            error->all(FLERR, "model mc_advanced: native/mcdem.h and the mcdem library disagree on the size of "
                              "mcdem_pair_batch (rebuild both from one checkout)");
        // Walls must see the same radius changes as pairs: give every granular wall its store now,
        // during the pair's init, so that the fixes created here are initialised with the others.
        const int nwalls = modify->n_fixes_style("wall/gran");
        for (int w = 0; w < nwalls; w++) {
            FixWallGran *fwg = static_cast<FixWallGran *>(modify->find_fix_style("wall/gran", w));
            if (!fwg->contact_match("normal", "mc_advanced")) {
                char msg[256];
                std::snprintf(msg, sizeof(msg),
                              "fix %s: walls must use `model mc_advanced` when the pair style does "
                              "(a wall contact deforms the particle at its other contacts)",
                              fwg->id);
                error->all(FLERR, msg);
            }
            if (fwg->is_mesh_wall()) {
                for (int m = 0; m < fwg->n_meshes(); m++) fwg->mesh_list()[m]->createMulticontactData();
            } else {
                fwg->createMulticontactData();
            }
        }
        sources_ready_ = false;
    }

    double stressStrainExponent() { return 1.5; }

    void beginPass(SurfacesIntersectData &sidata, ForceData &, ForceData &) {
        // The pair pass starts each force evaluation: the records of the previous step are
        // complete (walls included) and nothing has used radii yet, so the radius changes of this
        // step are computed here. Passes that only collect data (computeflag 0) reuse them.
        if (cmb_->is_wall() || !sidata.computeflag) return;
        // `updateEvery K`: between updates the stores keep the last radius changes. A neighbour
        // build (every run's set-up included) exchanges and re-sorts atoms and re-points the wall
        // rows, so a step with a build always updates.
        const bigint now = update->ntimestep;
        if (update_every_ > 1 && last_update_ >= 0 && now > last_update_ && now - last_update_ < update_every_ &&
            neighbor->lastcall <= last_update_)
            return;
        last_update_ = now;
        update_radius_changes();
    }

    void endPass(SurfacesIntersectData &, ForceData &, ForceData &) {}

    void surfacesIntersect(SurfacesIntersectData &sidata, ForceData &i_forces, ForceData &j_forces) {
        if (sidata.contact_flags) *sidata.contact_flags |= CONTACT_NORMAL_MODEL;
        const int it = sidata.itype, jt = sidata.jtype;
        const double radj = sidata.radj;
        const double radi = stock_pair_radii_ ? sidata.radi : modified_radius_i(sidata);
        if (!sidata.is_wall && !stock_pair_radii_) use_modified_lever_arms(sidata, radi);
        const double reff = sidata.is_wall ? radi : radi * radj / (radi + radj);
        // Radii shrunk by the multi-contact correction can leave a geometric touch with no
        // effective overlap (or no positive effective radius): that contact carries no force.
        const double deltan = reff > 0.0 ? sidata.deltan : 0.0;
        // The overlap must stay below the smaller original radius (what the batched path and
        // `mcdem run` stop on too): beyond it the particles pass through each other.
        const double *radius = atom->radius;
        const double rmin = sidata.is_wall ? radius[sidata.i] : std::min(radius[sidata.i], radius[sidata.j]);
        mcdem_normal_force nf;
        if (mcdem_check_overlap(sidata.deltan, rmin) != MCDEM_OK ||
            mcdem_hertz_normal(&coeffs_[it][jt], deltan, reff, sidata.meff, sidata.vn, &nf) != MCDEM_OK)
            stop_at_contact(lmp, sidata.i, sidata.is_wall ? -1 : sidata.j, last_mcdem_error());
        double fn = nf.force;
        if (limit_force_ && fn < 0.0) fn = 0.0;
        sidata.Fn = fn;
        sidata.kn = nf.kn / force->nktv2p;
        sidata.kt = nf.kt / force->nktv2p;
        sidata.gamman = nf.gamma_n;
        sidata.gammat = tangential_damping_ ? nf.gamma_t : 0.0;
        const double applied = sidata.is_wall ? fn * sidata.area_ratio : fn;
        for (int k = 0; k < 3; k++) {
            i_forces.delta_F[k] += applied * sidata.en[k];
            if (!sidata.is_wall) j_forces.delta_F[k] -= applied * sidata.en[k];
        }
        if (sidata.computeflag && sidata.shearupdate && sidata.contact_history) {
            double *rec = &sidata.contact_history[record_offset_];
            if (sidata.is_wall) {
                for (int k = 0; k < 3; k++) rec[k] = -sidata.delta[k];
                rec[3] = std::fabs(applied);
            } else {
                write_pair_record(rec, sidata.i, sidata.j, radi, radj, std::fabs(applied));
            }
        }
    }

    void surfacesClose(SurfacesCloseData &scdata, ForceData &, ForceData &) {
        if (scdata.contact_flags) *scdata.contact_flags |= CONTACT_NORMAL_MODEL;
        if (!(scdata.computeflag && scdata.shearupdate && scdata.contact_history)) return;
        // A close, untouching pair is still recorded (with zero force) so that the radius change
        // it receives from the particle's other contacts can bring it into contact.
        double *rec = &scdata.contact_history[record_offset_];
        if (scdata.is_wall) {
            const double len = std::sqrt(scdata.delta[0] * scdata.delta[0] + scdata.delta[1] * scdata.delta[1] +
                                         scdata.delta[2] * scdata.delta[2]);
            const double s = len > 1e-15 ? -scdata.radi / len : 0.0;
            for (int k = 0; k < 3; k++) rec[k] = scdata.delta[k] * s;
            rec[3] = 0.0;
        } else {
            write_pair_record(rec, scdata.i, scdata.j, stock_pair_radii_ ? scdata.radi : modified_radius_i(scdata),
                              scdata.radj, 0.0);
        }
    }

    // A pair's record names its radii by atom ID (the partner with the smaller ID first), not by
    // the order of the neighbour list: a list build that names the partners the other way round
    // (atoms sorted or migrated) copies the history unchanged, so a record "i first" would hand
    // each partner the other's radius, and a wrong contact point, until the pair is next evaluated.
    void write_pair_record(double *rec, int i, int j, double radi, double radj, double fn) const {
        const bool i_first = atom->tag[i] < atom->tag[j];
        rec[0] = i_first ? radi : radj;
        rec[1] = i_first ? radj : radi;
        rec[2] = fn;
    }

    // Whether the pair loop may hand this model's overlapping pairs to the core in batches
    // (mcdem_pair_batch): the batch computes the contact of the default settings (both partners'
    // modified radii, tangential damping on, no limitForce) in SI units, where k_n, k_t need no
    // conversion. Any other setting keeps the one-contact path.
    bool batch_eligible() const {
        return !stock_pair_radii_ && !limit_force_ && tangential_damping_ && force->nktv2p == 1.0;
    }
    const mcdem_pair_coeffs &pair_coeffs(int it, int jt) const { return coeffs_[it][jt]; }

    // i's multi-contact-modified radius at this contact. LIGGGHTS's pair loop grows radj and the
    // radius sum but leaves radi at the original radius (its walls grow radi). SPEC §2 uses the
    // modified radius of both partners for R_eff, the lever arms and the contact point, so that a
    // pair does not depend on which partner the neighbour list names first.
    static double modified_radius_i(const SurfacesCloseData &d) { return d.is_wall ? d.radi : d.radsum - d.radj; }

    // The surface model computed the relative surface velocity and lever arms with radi; redo that
    // kinematics with the modified radius (same formulas, LIGGGHTS's sign conventions).
    static void use_modified_lever_arms(SurfacesIntersectData &d, double radi) {
        const double cri = radi - 0.5 * d.deltan;
        const double crj = d.radj - 0.5 * d.deltan;
        double wr[3], vt[3];
        for (int k = 0; k < 3; k++) {
            wr[k] = (cri * d.omega_i[k] + crj * d.omega_j[k]) * d.rinv;
            vt[k] = (d.v_i[k] - d.v_j[k]) - d.vn * d.en[k];
        }
        d.cri = cri;
        d.crj = crj;
        d.wr1 = wr[0];
        d.wr2 = wr[1];
        d.wr3 = wr[2];
        d.vtr1 = vt[0] - (d.delta[2] * wr[1] - d.delta[1] * wr[2]);
        d.vtr2 = vt[1] - (d.delta[0] * wr[2] - d.delta[2] * wr[0]);
        d.vtr3 = vt[2] - (d.delta[1] * wr[0] - d.delta[0] * wr[1]);
    }

private:
    // Stops a deck whose wall gives a shared setting (see SharedSetting) another value than the
    // pair style's, instead of ignoring it.
    void check_wall_settings() const {
        std::map<LAMMPS *, NormalModel *>::const_iterator it = pair_models_.find(lmp);
        if (it == pair_models_.end()) return;
        const NormalModel *p = it->second;
        char mine[64], theirs[64];
        const char *name = NULL;
        if (given_[kMprTest] && signed_test_ != p->signed_test_) {
            name = "mprTest";
            std::snprintf(mine, sizeof(mine), "%s", signed_test_ ? "signed" : "abs");
            std::snprintf(theirs, sizeof(theirs), "%s", p->signed_test_ ? "signed" : "abs");
        } else if (given_[kGeometryTolerance] && geometry_tolerance_ != p->geometry_tolerance_) {
            name = "geometryTolerance";
            std::snprintf(mine, sizeof(mine), "%g", geometry_tolerance_);
            std::snprintf(theirs, sizeof(theirs), "%g", p->geometry_tolerance_);
        } else if (given_[kUpdateEvery] && update_every_ != p->update_every_) {
            name = "updateEvery";
            std::snprintf(mine, sizeof(mine), "%d", update_every_);
            std::snprintf(theirs, sizeof(theirs), "%d", p->update_every_);
        }
        if (!name) return;
        char msg[512];
        std::snprintf(msg, sizeof(msg),
                      "fix wall/gran with model mc_advanced: %s %s differs from the pair style's %s %s (the pair "
                      "style computes the radius changes of every contact, walls included: set it there, or "
                      "repeat its value here)",
                      name, mine, name, theirs);
        error->all(FLERR, msg);
    }

    FixPropertyGlobal *find_property(const char *name, const char *kind, int len, const char *usage) {
        Fix *f = modify->find_fix_property(name, "property/global", kind, len, 0, "model mc_advanced", false);
        if (!f) {
            char msg[512];
            std::snprintf(msg, sizeof(msg),
                          "model mc_advanced needs property %s: add `fix ID all property/global %s %s` %s",
                          name, name, kind, usage);
            error->all(FLERR, msg);
        }
        return static_cast<FixPropertyGlobal *>(f);
    }

    // Reads the material per atom type, validates it through the core and builds the pair
    // coefficient table (one entry per type pair, walls have their own atom type).
    void read_materials() {
        const int n = atom->get_properties()->max_type();
        char usage[64];
        std::snprintf(usage, sizeof(usage), "(%d values, one per atom type)", n);
        char usage_pair[64];
        std::snprintf(usage_pair, sizeof(usage_pair), "%d followed by %d values", n, n * n);
        const double *E = find_property("youngsModulus", "peratomtype", n, usage)->get_values();
        const double *nu = find_property("poissonsRatio", "peratomtype", n, usage)->get_values();
        const double *gamma = find_property("geometricPrefactor", "peratomtype", n, usage)->get_values();
        const double *mpr = find_property("maxPenetrationRatio", "peratomtype", n, usage)->get_values();
        FixPropertyGlobal *rest = find_property("coefficientRestitution", "peratomtypepair", n, usage_pair);
        Fix *fric_fix = modify->find_fix_property("coefficientFriction", "property/global", "peratomtypepair", n, n,
                                                  "model mc_advanced", false);
        FixPropertyGlobal *fric = static_cast<FixPropertyGlobal *>(fric_fix);

        ntypes_ = n;
        params_.assign(n + 1, mcdem_mc_params());
        coeffs_.assign(n + 1, std::vector<mcdem_pair_coeffs>(n + 1));
        for (int t = 1; t <= n; t++) {
            mcdem_mc_params p;
            p.radius = 1.0;  // placeholder: the real radius is per particle, set at each call
            p.youngs_modulus = E[t - 1];
            p.poisson_ratio = nu[t - 1];
            p.gamma = gamma[t - 1];
            p.mpr = mpr[t - 1];
            p.cap = signed_test_ ? MCDEM_CAP_SIGNED : MCDEM_CAP_ABS;
            if (mcdem_validate_mc_params(&p) != MCDEM_OK) fail_property(t, last_mcdem_error());
            params_[t] = p;
        }
        for (int a = 1; a <= n; a++) {
            for (int b = 1; b <= n; b++) {
                const double e = rest->compute_array(a - 1, b - 1);
                const double mu = fric ? fric->compute_array(a - 1, b - 1) : 0.0;
                if (mcdem_pair_coeffs_new(E[a - 1], nu[a - 1], E[b - 1], nu[b - 1], e, mu, &coeffs_[a][b]) !=
                    MCDEM_OK) {
                    char msg[700];
                    std::snprintf(msg, sizeof(msg),
                                  "model mc_advanced, atom types %d and %d (coefficientRestitution / "
                                  "coefficientFriction): %s",
                                  a, b, last_mcdem_error().c_str());
                    error->all(FLERR, msg);
                }
            }
        }
    }

    void fail_property(int type, const std::string &core_msg) {
        // Name the LIGGGHTS property a user has to change, not the core's field.
        const char *prop = "a material property";
        if (core_msg.find("poisson") != std::string::npos) prop = "poissonsRatio";
        else if (core_msg.find("young") != std::string::npos) prop = "youngsModulus";
        else if (core_msg.find("gamma") != std::string::npos) prop = "geometricPrefactor";
        else if (core_msg.find("mpr") != std::string::npos) prop = "maxPenetrationRatio";
        char msg[700];
        std::snprintf(msg, sizeof(msg), "model mc_advanced: invalid %s for atom type %d (%s)", prop, type,
                      core_msg.c_str());
        error->all(FLERR, msg);
    }

    void collect_sources() {
        sources_.clear();
        PairGranProxy *pg = static_cast<PairGranProxy *>(force->pair_match("gran", 0));
        FixContactPropertyAtom *pair_store =
            static_cast<FixContactPropertyAtom *>(modify->find_fix_id("multicontactData_"));
        if (!pair_store) error->all(FLERR, "model mc_advanced: the pair style's per-contact store was not created");
        sources_.push_back(McSource(HistoryData('p', (void *)pg, record_offset_), pair_store, false, false, NULL));

        const int nwalls = modify->n_fixes_style("wall/gran");
        for (int w = 0; w < nwalls; w++) {
            FixWallGran *fwg = static_cast<FixWallGran *>(modify->find_fix_style("wall/gran", w));
            if (fwg->get_history_offset(kRecordName) != 0) {
                char msg[256];
                std::snprintf(msg, sizeof(msg),
                              "fix %s: model mc_advanced expects its contact record first in the wall history", fwg->id);
                error->all(FLERR, msg);
            }
            char fixid[256];
            if (fwg->is_mesh_wall()) {
                for (int m = 0; m < fwg->n_meshes(); m++) {
                    FixMeshSurface *mesh = fwg->mesh_list()[m];
                    std::snprintf(fixid, sizeof(fixid), "tracker_%s", mesh->id);
                    Fix *tracker = modify->find_fix_id(fixid);
                    FixContactPropertyAtom *store = mesh->meshMulticontactData();
                    FixPropertyAtom *nneighs = mesh->meshNeighlist() ? mesh->meshNeighlist()->fix_nneighs() : NULL;
                    if (!tracker || !store || !nneighs) {
                        std::snprintf(fixid, sizeof(fixid),
                                      "fix %s: mesh %s has no contact tracker, store or neighbour list", fwg->id,
                                      mesh->id);
                        error->all(FLERR, fixid);
                    }
                    sources_.push_back(McSource(HistoryData('m', (void *)tracker, 0), store, true, false, nneighs));
                }
            } else {
                std::snprintf(fixid, sizeof(fixid), "history_%s", fwg->id);
                Fix *hist = modify->find_fix_id(fixid);
                std::snprintf(fixid, sizeof(fixid), "multicontactData_%s", fwg->id);
                FixContactPropertyAtom *store = static_cast<FixContactPropertyAtom *>(modify->find_fix_id(fixid));
                if (!hist || !store) {
                    std::snprintf(fixid, sizeof(fixid), "fix %s: primitive wall has no contact history or store",
                                  fwg->id);
                    error->all(FLERR, fixid);
                }
                sources_.push_back(McSource(HistoryData('w', (void *)hist, 0), store, true, true, NULL));
            }
        }
        sources_ready_ = true;
    }

    void update_radius_changes() {
        if (!sources_ready_) collect_sources();
        if (geometry_tolerance_ > 0.0 && !cache_) {
            cache_ = mcdem_influence_cache_new(geometry_tolerance_);
            if (!cache_) error->all(FLERR, ("model mc_advanced: " + last_mcdem_error()).c_str());
        }
        for (size_t s = 0; s < sources_.size(); s++) {
            if (sources_[s].wall) {
                static_cast<FixContactPropertyAtomWall *>(sources_[s].store)->clear();
                empty_wall_rows(sources_[s]);
            } else {
                sources_[s].store->clear();
            }
        }
        const int nlocal = atom->nlocal;
        double **x = atom->x;
        const int *tag = atom->tag;
        const int *type = atom->type;
        const double *radius = atom->radius;
        pair_rows_.clear();

        // 1. Contact points and previous-step forces of every recorded contact, stored on both
        //    partners of a pair (the library's store keeps one row per partner: point + force).
        for (int i = 0; i < nlocal; i++) {
            const mcdem_mc_params &p = params_[type[i]];
            const double f_eps = p.youngs_modulus * radius[i] * radius[i] * 1e-14;
            gather_pair_records(i, f_eps);
            for (size_t s = 1; s < sources_.size(); s++) {
                HistoryData &h = sources_[s].history;
                const int n = h.get_npartners(i);
                for (int jj = 0; jj < n; jj++) {
                    double *rec = h.get_data_ptr(i, jj);
                    // A wall contact never close enough to be recorded has no contact surface.
                    if (rec[0] == 0.0 && rec[1] == 0.0 && rec[2] == 0.0) continue;
                    double pij[4], pji[4];
                    h.compute_surfPos(i, jj, x, rec, pij, pji, f_eps);
                    pij[3] = pji[3] = h.get_fn(rec);
                    if (h.get_type() == 'm') {
                        // The library's HistoryData names the row by the triangle in the tracker's
                        // jj-th slot, while the record it read is that of the jj-th contact (slots
                        // freed by ended contacts are skipped): the slot's own triangle is used here.
                        FixContactHistoryMesh *tracker = static_cast<FixContactHistoryMesh *>(h.get_ptr());
                        const int id_tri = tracker->get_partner_idTri(i, tracker->get_contact(i, jj));
                        sources_[s].store->add_partner(i, id_tri, pij);
                    } else {
                        h.save_contact_property_atom(i, jj, tag, pij, pji, sources_[s].store);
                    }
                }
            }
        }

        // 2. Radius change per contact from the core; particles with fewer than two contacts have
        //    no neighbour term and are not sent.
        for (int i = 0; i < nlocal; i++) {
            rows_.clear();
            for (size_t s = 0; s < sources_.size(); s++) {
                FixContactPropertyAtom *st = sources_[s].store;
                const int n = st->get_npartners(i);
                for (int c = 0; c < n; c++) rows_.push_back(st->contacthistory(i, c));
            }
            const size_t n = rows_.size();
            if (n < 2) {
                for (size_t c = 0; c < n; c++) rows_[c][3] = 0.0;
                continue;
            }
            loads_.resize(n);
            delta_.resize(n);
            fallback_.resize(n);
            for (size_t c = 0; c < n; c++) {
                for (int k = 0; k < 3; k++) loads_[c].point[k] = rows_[c][k];
                loads_[c].force = rows_[c][3];
            }
            mcdem_mc_params p = params_[type[i]];
            p.radius = radius[i];
            // With a geometry tolerance the slot is the local index: after a sort or an exchange it
            // holds another particle, whose points differ, so the store recomputes (it tests points,
            // not identities).
            const int32_t rc =
                cache_ ? mcdem_radius_changes_cached(cache_, static_cast<size_t>(i), &p, &loads_[0], n, &delta_[0],
                                                     &fallback_[0], NULL)
                       : mcdem_radius_changes(&p, &loads_[0], n, &delta_[0], &fallback_[0], NULL);
            if (rc != MCDEM_OK) {
                char msg[700];
                std::snprintf(msg, sizeof(msg), "model mc_advanced: particle %d, step " BIGINT_FORMAT ": %s", tag[i],
                              update->ntimestep, last_mcdem_error().c_str());
                error->one(FLERR, msg);
            }
            for (size_t c = 0; c < n; c++) rows_[c][3] = delta_[c];
        }

        // 3. Ghost copies see their owners' radius changes (with several MPI ranks a pair across a
        //    sub-domain boundary reads its partner's row from the ghost).
        for (size_t s = 0; s < sources_.size(); s++) sources_[s].store->do_forward_comm();

        // 4. Both partners' radius changes into each pair's record, where the pair loop reads them.
        copy_to_pair_records();
    }

    // The pair source's records (sources_[0]) in place: the contact history of neighbour-list
    // entry (i, jj), where HistoryData's accessor would find it, and its partner.
    struct PairRecords {
        const NeighList *list;
        FixContactPropertyAtom *store;
        double **hist;
        int dnum, offset;
        double *at(int i, int jj) const { return &hist[i][jj * dnum + offset]; }
        int partner(int i, int jj) const { return list->firstneigh[i][jj] & NEIGHMASK; }
    };
    PairRecords pair_records() {
        const NeighList *list = static_cast<PairGranProxy *>(sources_[0].history.get_ptr())->list;
        PairRecords pr = {list, sources_[0].store, list->listgranhistory->firstdouble, list->listgranhistory->dnum,
                          record_offset_};
        return pr;
    }

    // Step 1 for the pair source (sources_[0]): its records are the contact histories of the
    // neighbour-list entries, read in place (what HistoryData's accessors do, without a call and a
    // type switch per record). The contact points still come from the library's compute_surfPos.
    void gather_pair_records(int i, double f_eps) {
        const PairRecords pr = pair_records();
        FixContactPropertyAtom *st = pr.store;
        const int nlocal = atom->nlocal;
        const int *tag = atom->tag;
        for (int jj = 0; jj < pr.list->numneigh[i]; jj++) {
            const double *rec = pr.at(i, jj);
            // A neighbour never close enough to be recorded has no contact surface.
            if (rec[0] == 0.0 && rec[1] == 0.0) continue;
            const int j = pr.partner(i, jj);
            // The library's layout: this list entry's r_i', r_j', |F_n|.
            const bool i_first = tag[i] < tag[j];
            const double oriented[3] = {i_first ? rec[0] : rec[1], i_first ? rec[1] : rec[0], rec[2]};
            double pij[4], pji[4];
            sources_[0].history.compute_surfPos(i, jj, atom->x, oriented, pij, pji, f_eps);
            pij[3] = pji[3] = rec[2];
            // add_partner appends: the rows this record fills are the current ends, known here so
            // that step 4 needs no search (ghost rows are replaced by the forward communication,
            // so a ghost partner is searched there).
            pair_rows_.push_back(PairRow(i, jj, st->get_npartners(i), j < nlocal ? st->get_npartners(j) : -1));
            st->add_partner(i, tag[j], pij);
            st->add_partner(j, tag[i], pji);
        }
    }

    // The pair loop needs, for every neighbour pair (i, j), the radius change of i at j and of j at
    // i: the values the store holds under the partner's ID, or 0 where it holds none. The
    // library's loop searches the store for them twice per neighbour pair and step; here they are
    // taken once per update from the rows step 1 filled (a search only for ghost partners, whose
    // rows the forward communication brought) and kept in the pair's record by atom ID, like its
    // radii, so the loop reads them directly. Same values, so the same forces bit for bit.
    void copy_to_pair_records() {
        const PairRecords pr = pair_records();
        FixContactPropertyAtom *st = pr.store;
        const int nlocal = atom->nlocal;
        const int *tag = atom->tag;
        for (int i = 0; i < nlocal; i++) {
            for (int jj = 0; jj < pr.list->numneigh[i]; jj++) {
                double *rec = pr.at(i, jj);
                const int j = pr.partner(i, jj);
                double dri = 0.0, drj = 0.0;
                if (j >= nlocal) {
                    const int ci = st->has_partner(i, tag[j]);
                    const int cj = st->has_partner(j, tag[i]);
                    if (ci != -1) dri = st->contacthistory(i, ci)[3];
                    if (cj != -1) drj = st->contacthistory(j, cj)[3];
                }
                write_pair_radius_changes(rec, tag[i] < tag[j], dri, drj);
            }
        }
        for (size_t k = 0; k < pair_rows_.size(); k++) {
            const PairRow &r = pair_rows_[k];
            if (r.row_j < 0) continue;
            const int j = pr.partner(r.i, r.jj);
            write_pair_radius_changes(pr.at(r.i, r.jj), tag[r.i] < tag[j],
                                      st->contacthistory(r.i, r.row_i)[3],
                                      st->contacthistory(j, r.row_j)[3]);
        }
    }

    static void write_pair_radius_changes(double *rec, bool i_first, double dri, double drj) {
        rec[kPairDrLo] = i_first ? dri : drj;
        rec[kPairDrHi] = i_first ? drj : dri;
    }

    // Empties a wall store's rows for this step (see McSource). Mesh walls keep the library's rows:
    // their number per particle, the triangles near it, is what the wall loop searches. A primitive
    // wall's rows are pointed at one row per particle (owned and ghost) owned here; the library
    // points them back at its own storage at the next neighbour-list build, before they are used.
    void empty_wall_rows(McSource &src) {
        FixContactPropertyAtom *st = src.store;
        int **partner = st->*private_member(PartnerTag());
        double **rows = st->*private_member(RowsTag());
        const int nall = atom->nlocal + atom->nghost;
        if (src.primitive) {
            const size_t dnum = st->get_dnum();
            src.own_partner.assign(nall, -1);
            src.own_rows.assign(nall * dnum, 0.0);
            for (int i = 0; i < nall; i++) {
                partner[i] = &src.own_partner[i];
                rows[i] = &src.own_rows[i * dnum];
            }
        } else {
            for (int i = 0; i < nall; i++) {
                const int n = src.mesh_nneighs->get_vector_atom_int(i);
                for (int k = 0; k < n; k++) partner[i][k] = -1;
            }
        }
    }

    ContactModelBase *cmb_;
    int record_offset_;
    bool tangential_damping_;
    bool limit_force_;
    bool signed_test_;
    // `pairRadii stock`: pairs keep LIGGGHTS's convention (first partner's original radius in R_eff,
    // lever arm and contact point), to reproduce decks run with the stock `surface multicontact`.
    bool stock_pair_radii_;
    // `geometryTolerance TOL` (> 0): each particle's influence matrix is kept in cache_ (slot = local
    // index) until one of its contact points moved more than TOL x radius; 0 is the exact kernel.
    double geometry_tolerance_;
    // `updateEvery K`: radius changes recomputed every K steps and at neighbour builds (1: every step).
    int update_every_;
    bigint last_update_;
    mcdem_influence_cache *cache_;
    int ntypes_;
    std::vector<mcdem_mc_params> params_;
    std::vector<std::vector<mcdem_pair_coeffs> > coeffs_;
    bool sources_ready_;
    std::vector<McSource> sources_;
    // Step 1's pair records: list entry (i, jj) and the store rows of i and of a local j it filled.
    struct PairRow {
        int i, jj, row_i, row_j;
        PairRow(int i_, int jj_, int ri, int rj) : i(i_), jj(jj_), row_i(ri), row_j(rj) {}
    };
    std::vector<PairRow> pair_rows_;
    std::vector<double *> rows_;
    std::vector<mcdem_contact_load> loads_;
    std::vector<double> delta_;
    std::vector<uint8_t> fallback_;
    // Which shared settings this model's deck line gave (SharedSetting order).
    bool given_[kSharedSettings];
    // The pair style's model of each LIGGGHTS instance (set when its settings are parsed), whose
    // shared settings apply to the instance's walls. Keyed by instance: a program may open several.
    static std::map<LAMMPS *, NormalModel *> pair_models_;
};

std::map<LAMMPS *, NormalModel<MC_ADVANCED> *> NormalModel<MC_ADVANCED>::pair_models_;

}  // namespace ContactModels
}  // namespace LIGGGHTS

namespace {

typedef ContactModel<GranStyle<MC_ADVANCED, TANGENTIAL_HISTORY, COHESION_OFF, ROLLING_OFF, SURFACE_DEFAULT> >
    McHistoryModel;
typedef ContactModel<GranStyle<MC_ADVANCED, TANGENTIAL_NO_HISTORY, COHESION_OFF, ROLLING_OFF, SURFACE_DEFAULT> >
    McNoHistoryModel;
typedef TangentialModel<TANGENTIAL_HISTORY> HistoryTangential;

// The batched pair path needs the sub-models of the `tangential history` combination, which
// ContactModel keeps private, and the tangential model's history offset and energy options (the
// batch computes none of them): the private-access idiom above, checked by the compiler.
struct McNormalTag {
    typedef NormalModel<MC_ADVANCED> McHistoryModel::*type;
    friend type private_member(McNormalTag);
};
template struct PrivateAccess<McNormalTag, &McHistoryModel::normalModel>;
struct McTangentialTag {
    typedef HistoryTangential McHistoryModel::*type;
    friend type private_member(McTangentialTag);
};
template struct PrivateAccess<McTangentialTag, &McHistoryModel::tangentialModel>;
struct ShearOffsetTag {
    typedef int HistoryTangential::*type;
    friend type private_member(ShearOffsetTag);
};
template struct PrivateAccess<ShearOffsetTag, &HistoryTangential::history_offset>;
template <int K>
struct TangentialFlagTag {
    typedef bool HistoryTangential::*type;
    friend type private_member(TangentialFlagTag);
};
template struct PrivateAccess<TangentialFlagTag<0>, &HistoryTangential::heating>;
template struct PrivateAccess<TangentialFlagTag<1>, &HistoryTangential::heating_track>;
template struct PrivateAccess<TangentialFlagTag<2>, &HistoryTangential::elasticpotflag_>;
template struct PrivateAccess<TangentialFlagTag<3>, &HistoryTangential::dissipatedflag_>;

// The pair batch of one force pass: overlapping pairs gathered lane by lane into the core's
// mcdem_pair_batch, evaluated eight at a time by mcdem_pair_batch_evaluate (the same contact as the
// one-contact path: Hertz normal force on the modified radii, damping, history tangential force),
// and their forces, torques, tangential histories and records written back. Used where the batch
// computes exactly what the sub-models would (see McBatch::open); every other pair takes the
// one-contact path.
class McBatch {
public:
    McBatch() : model_(NULL), used_(0) { std::memset(&b_, 0, sizeof(b_)); }

    // Ready for a pass of the history model when its settings and the pass's outputs allow it.
    bool open(LAMMPS *lmp, McHistoryModel &cmodel, PairGran *pg, bool extra_outputs) {
        HistoryTangential &tm = cmodel.*private_member(McTangentialTag());
        const NormalModel<MC_ADVANCED> &nm = cmodel.*private_member(McNormalTag());
        if (extra_outputs || !nm.batch_eligible() || tm.*private_member(TangentialFlagTag<0>()) ||
            tm.*private_member(TangentialFlagTag<1>()) || tm.*private_member(TangentialFlagTag<2>()) ||
            tm.*private_member(TangentialFlagTag<3>()) || !lmp->atom->sphere_flag || !lmp->atom->rmass ||
            pg->fr_pair() || !pg->computeflag() || !pg->shearupdate() || !pg->listgranhistory ||
            !pg->storeSumDelta())
            return false;
        lmp_ = lmp;
        pg_ = pg;
        model_ = &nm;
        shear_ = tm.*private_member(ShearOffsetTag());
        record_ = cmodel.get_history_offset(kRecordName);
        dnum_ = pg->dnum();
        dt_ = lmp->update->dt;
        return true;
    }

    // Neighbour entry jj of i (partner j, centre difference del, radius changes dri, drj at this
    // contact) into the next lane.
    void push(int i, int j, int jj, const double *del, double dri, double drj) {
        const Atom *atom = lmp_->atom;
        const int l = used_;
        double **v = atom->v, **omega = atom->omega;
        const double *hist = &pg_->listgranhistory->firstdouble[i][dnum_ * jj + shear_];
        for (int k = 0; k < 3; k++) {
            b_.d[k][l] = del[k];
            b_.vr[k][l] = v[i][k] - v[j][k];
            b_.omega_i[k][l] = omega[i][k];
            b_.omega_j[k][l] = omega[j][k];
            b_.shear[k][l] = hist[k];
        }
        b_.radius_i[l] = atom->radius[i];
        b_.radius_j[l] = atom->radius[j];
        b_.dri[l] = dri;
        b_.drj[l] = drj;
        b_.mass_i[l] = atom->rmass[i];
        b_.mass_j[l] = atom->rmass[j];
        const mcdem_pair_coeffs &c = model_->pair_coeffs(atom->type[i], atom->type[j]);
        b_.e_star[l] = c.e_star;
        b_.g_star[l] = c.g_star;
        b_.beta[l] = c.beta;
        b_.friction[l] = c.friction;
        b_.damping_ratio_t_n[l] = c.damping_ratio_t_n;
        i_[l] = i;
        j_[l] = j;
        jj_[l] = jj;
        if (++used_ == MCDEM_BATCH_LANES) flush();
    }

    // Evaluates the lanes filled so far and writes their results where the sub-models would.
    void flush() {
        if (!used_) return;
        if (mcdem_pair_batch_evaluate(&b_, static_cast<size_t>(used_), dt_) != MCDEM_OK)
            lmp_->error->one(FLERR, ("model mc_advanced: " + last_mcdem_error()).c_str());
        Atom *atom = lmp_->atom;
        double **f = atom->f, **torque = atom->torque;
        const int nlocal = atom->nlocal;
        const bool newton_pair = lmp_->force->newton_pair;
        int **flags = pg_->listgranhistory->firstneigh;
        for (int l = 0; l < used_; l++) {
            if (!b_.ok[l]) fail(l);
            const int i = i_[l], j = j_[l];
            double *hist = &pg_->listgranhistory->firstdouble[i][dnum_ * jj_[l]];
            for (int k = 0; k < 3; k++) hist[shear_ + k] = b_.shear[k][l];
            if (flags) flags[i][jj_[l]] |= CONTACT_NORMAL_MODEL | CONTACT_TANGENTIAL_MODEL;
            // The modified radii as the loop and the core form them: original radius + change.
            model_->write_pair_record(&hist[record_], i, j, b_.radius_i[l] + b_.dri[l], b_.radius_j[l] + b_.drj[l],
                                      std::fabs(b_.normal[l]));
            const double F[3] = {b_.force[0][l], b_.force[1][l], b_.force[2][l]};
            const double relax_i = pg_->relax(i);
            for (int k = 0; k < 3; k++) {
                f[i][k] += relax_i * F[k];
                torque[i][k] += relax_i * b_.torque_i[k][l];
            }
            if (newton_pair || j < nlocal) {
                const double relax_j = pg_->relax(j);
                for (int k = 0; k < 3; k++) {
                    f[j][k] += relax_j * -F[k];
                    torque[j][k] += relax_j * b_.torque_j[k][l];
                }
            }
            if (pg_->evflag)
                pg_->ev_tally_xyz(i, j, nlocal, newton_pair, 0.0, 0.0, F[0], F[1], F[2], b_.d[0][l], b_.d[1][l],
                                  b_.d[2][l]);
        }
        used_ = 0;
    }

private:
    // Stops the run at a lane the core could not integrate, with the core's reason for that pair.
    void fail(int l) const {
        mcdem_body bi, bj;
        for (int k = 0; k < 3; k++) {
            bi.x[k] = b_.d[k][l];
            bj.x[k] = 0.0;
            bi.v[k] = b_.vr[k][l];
            bj.v[k] = 0.0;
            bi.omega[k] = b_.omega_i[k][l];
            bj.omega[k] = b_.omega_j[k][l];
        }
        bi.radius = b_.radius_i[l];
        bj.radius = b_.radius_j[l];
        bi.mass = b_.mass_i[l];
        bj.mass = b_.mass_j[l];
        const double *hist = &pg_->listgranhistory->firstdouble[i_[l]][dnum_ * jj_[l] + shear_];
        double shear[3] = {hist[0], hist[1], hist[2]};
        mcdem_contact_force out;
        const Atom *atom = lmp_->atom;
        const bool explained =
            mcdem_particle_particle(&model_->pair_coeffs(atom->type[i_[l]], atom->type[j_[l]]), &bi, &bj, b_.dri[l],
                                    b_.drj[l], dt_, shear, &out) != MCDEM_OK;
        stop_at_contact(lmp_, i_[l], j_[l], explained ? last_mcdem_error() : std::string("contact force not finite"));
    }

    mcdem_pair_batch b_;
    LAMMPS *lmp_;
    PairGran *pg_;
    const NormalModel<MC_ADVANCED> *model_;
    int shear_, record_, dnum_;
    double dt_;
    int used_;
    int i_[MCDEM_BATCH_LANES], j_[MCDEM_BATCH_LANES], jj_[MCDEM_BATCH_LANES];
};

// The batch serves the `tangential history` combination; `no_history` keeps the one-contact path.
template <typename Model>
bool open_batch(McBatch &, LAMMPS *, Model &, PairGran *, bool) {
    return false;
}
template <>
bool open_batch(McBatch &batch, LAMMPS *lmp, McHistoryModel &cmodel, PairGran *pg, bool extra_outputs) {
    return batch.open(lmp, cmodel, pg, extra_outputs);
}

}  // namespace

namespace LIGGGHTS {
namespace PairStyles {

inline void add_force(double relax, double *f, double *torque, const ForceData &d) {
    for (int k = 0; k < 3; k++) {
        f[k] += relax * d.delta_F[k];
        torque[k] += relax * d.delta_torque[k];
    }
}

// A contact's force on `atom` from partner `partner_tag`, recorded once per step: force and torque
// (other < 0), or force and the partner's index (the stress store).
inline void store_partner_pair(FixContactPropertyAtom *store, int atom, int partner_tag, const ForceData &d,
                               int other) {
    if (store->has_partner(atom, partner_tag) != -1) return;
    double row[6];
    vectorCopy3D(d.delta_F, &row[0]);
    if (other < 0)
        vectorCopy3D(d.delta_torque, &row[3]);
    else
        row[3] = static_cast<double>(other);
    store->add_partner(atom, partner_tag, row);
}

// The pair loop of `model mc_advanced`. It evaluates the neighbour pairs as the library's loop
// for spheres does (same broad-phase tests, same sub-model calls, same outputs: forces and
// torques, virial, compute pair/gran/local, stored contact forces, summed normal forces), with
// one change: each partner's multi-contact radius change at the contact is read from the pair's
// record (copy_to_pair_records) instead of being searched for in the per-atom store, twice per
// neighbour pair and step. That search made a pair cost a fixed amount more than with `hertz`,
// whatever the multi-contact update interval.
template <typename Model>
void mc_pair_loop(LAMMPS *lmp, Model &cmodel, SurfacesIntersectData &sidata, ForceData &i_forces,
                  ForceData &j_forces, PairGran *pg, int eflag, int vflag, int addflag) {
    if (eflag || vflag)
        pg->ev_setup(eflag, vflag);
    else
        pg->evflag = pg->vflag_fdotr = 0;
    Atom *atom = lmp->atom;
    double **x = atom->x, **v = atom->v, **f = atom->f, **omega = atom->omega, **torque = atom->torque;
    const double *radius = atom->radius, *rmass = atom->rmass, *mass = atom->mass;
    const int *type = atom->type, *mask = atom->mask, *tag = atom->tag;
    const int nlocal = atom->nlocal;
    const bool newton_pair = lmp->force->newton_pair;
    const NeighList *list = pg->list;
    int **first_flag = pg->listgranhistory ? pg->listgranhistory->firstneigh : NULL;
    double **first_hist = pg->listgranhistory ? pg->listgranhistory->firstdouble : NULL;
    const int dnum = pg->dnum();
    // Where each pair's radius changes sit; without a record (no history) none are applied.
    const int rec = first_hist && pg->storeSumDelta() ? cmodel.get_history_offset(kRecordName) : -1;
    const int freeze_bit = pg->freeze_group_bit();
    const double close_sq = lmp->neighbor->contactDistanceFactor * lmp->neighbor->contactDistanceFactor;
    const bool store_forces = pg->storeContactForces() && lmp->update->ntimestep % pg->storeContactForcesEvery() == 0;
    const bool store_stress = pg->storeContactForcesStress();
    const bool pair_local = pg->cpl() && addflag;
    std::vector<FixInsertStreamPredefined *> inserters;
    for (int k = 0; k < lmp->modify->n_fixes_style("insert/stream/predefined"); k++) {
        FixInsertStreamPredefined *fi =
            static_cast<FixInsertStreamPredefined *>(lmp->modify->find_fix_style("insert/stream/predefined", k));
        if (fi->has_inserted()) inserters.push_back(fi);
    }

    const bool no_inserters = inserters.empty();

    std::memset(&sidata, 0, sizeof(SurfacesIntersectData));
    std::memset(&i_forces, 0, sizeof(ForceData));
    std::memset(&j_forces, 0, sizeof(ForceData));
    sidata.area_ratio = 1.0;
    sidata.is_wall = false;
    sidata.computeflag = pg->computeflag();
    sidata.shearupdate = pg->shearupdate();
    cmodel.beginPass(sidata, i_forces, j_forces);
    // Overlapping pairs go to the core in batches unless an output needs the sub-models' per-pair
    // data (pair/gran/local, stored contact forces, summed normal forces, inserted histories).
    McBatch batch;
    const bool batched = open_batch(batch, lmp, cmodel, pg,
                                    pair_local || store_forces || store_stress || pg->store_sum_normal_force() ||
                                        !inserters.empty());

    for (int ii = 0; ii < list->inum; ii++) {
        const int i = list->ilist[ii];
        int *flags = first_flag ? first_flag[i] : NULL;
        double *hist = first_hist ? first_hist[i] : NULL;
        const int *jlist = list->firstneigh[i];
        sidata.i = i;
        // The library's convention: radi stays the original radius, radj and the radius sum
        // carry the radius changes (NormalModel<MC_ADVANCED> recovers i's from their difference).
        sidata.radi = radius[i];
        for (int jj = 0; jj < list->numneigh[i]; jj++) {
            const int j = jlist[jj] & NEIGHMASK;
            double del[3];
            for (int k = 0; k < 3; k++) del[k] = x[i][k] - x[j][k];
            const double rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
            double dri = 0.0, drj = 0.0;
            if (rec >= 0) {
                const double *r = &hist[dnum * jj + rec];
                const bool i_first = tag[i] < tag[j];
                dri = r[i_first ? kPairDrLo : kPairDrHi];
                drj = r[i_first ? kPairDrHi : kPairDrLo];
            }
            const double radi = radius[i] + dri, radj = radius[j] + drj;
            const double radsum = radi + radj;
            const double reach_sq = radsum * radsum;
            if (rsq >= reach_sq) {
                // Apart, and beyond the contact distance: the library's loop does nothing with the
                // pair either (no sub-model call, no output) except copy an inserted history.
                // Most neighbour pairs are of this kind (the skin), so they leave before the
                // per-pair set-up below.
                if (no_inserters && rsq >= close_sq * reach_sq) continue;
            } else if (batched && !((mask[i] | mask[j]) & freeze_bit)) {
                batch.push(i, j, jj, del, dri, drj);
                continue;
            }
            sidata.radj = radj;
            sidata.radsum = radsum;
            sidata.j = j;
            for (int k = 0; k < 3; k++) sidata.delta[k] = del[k];
            sidata.rsq = rsq;
            sidata.contact_flags = flags ? &flags[jj] : NULL;
            sidata.contact_history = hist ? &hist[dnum * jj] : NULL;
            for (size_t k = 0; k < inserters.size(); k++) inserters[k]->copy_history(i, j, sidata.contact_history);
            i_forces.reset();
            j_forces.reset();
            sidata.v_i = v[i];
            sidata.v_j = v[j];
            sidata.itype = type[i];
            sidata.jtype = type[j];

            if (rsq < reach_sq && cmodel.checkSurfaceIntersect(sidata)) {
                const double r = std::sqrt(rsq);
                const double rinv = 1.0 / r;
                double mi = rmass ? rmass[i] : mass[type[i]];
                double mj = rmass ? rmass[j] : mass[type[j]];
                if (pg->fr_pair()) {
                    const double *mr = pg->mr_pair();
                    if (mr[i] > 0.0) mi = mr[i];
                    if (mr[j] > 0.0) mj = mr[j];
                }
                double meff = mi * mj / (mi + mj);
                if (mask[i] & freeze_bit) meff = mj;
                if (mask[j] & freeze_bit) meff = mi;
                sidata.r = r;
                sidata.rinv = rinv;
                sidata.meff = meff;
                sidata.mi = mi;
                sidata.mj = mj;
                if (atom->sphere_flag)
                    for (int k = 0; k < 3; k++) sidata.en[k] = del[k] * rinv;
                sidata.omega_i = omega[i];
                sidata.omega_j = omega[j];
                cmodel.surfacesIntersect(sidata, i_forces, j_forces);
                cmodel.endSurfacesIntersect(sidata, 0, i_forces, j_forces);
                sidata.has_force_update = true;
            } else if (rsq < close_sq * reach_sq && !atom->shapetype_flag) {
                sidata.has_force_update = false;
                cmodel.surfacesClose(sidata, i_forces, j_forces);
            } else {
                sidata.has_force_update = false;
            }
            if (!sidata.has_force_update) continue;

            if (sidata.computeflag) {
                add_force(pg->relax(i), f[i], torque[i], i_forces);
                if (newton_pair || j < nlocal) add_force(pg->relax(j), f[j], torque[j], j_forces);
                if (pg->store_sum_normal_force()) {
                    const double fdotn = vectorDot3D(i_forces.delta_F, sidata.en);
                    *pg->get_sum_normal_force_ptr(i) += fdotn;
                    if (newton_pair || j < nlocal) *pg->get_sum_normal_force_ptr(j) += fdotn;
                }
            }
            if (pair_local) pg->cpl_add_pair(sidata, i_forces);
            if (pg->evflag)
                pg->ev_tally_xyz(i, j, nlocal, newton_pair, 0.0, 0.0, i_forces.delta_F[0], i_forces.delta_F[1],
                                 i_forces.delta_F[2], del[0], del[1], del[2]);
            if (store_forces) {
                store_partner_pair(pg->fix_contact_forces(), i, tag[j], i_forces, -1);
                store_partner_pair(pg->fix_contact_forces(), j, tag[i], j_forces, -1);
            }
            if (store_stress) {
                store_partner_pair(pg->fix_contact_forces_stress(), i, tag[j], i_forces, j);
                store_partner_pair(pg->fix_contact_forces_stress(), j, tag[i], j_forces, i);
            }
        }
    }

    if (batched) batch.flush();
    cmodel.endPass(sidata, i_forces, j_forces);
    if (pair_local) pg->cpl_pair_finalize();
    if (pg->storeContactForces()) pg->fix_contact_forces()->do_forward_comm();
    if (store_stress) pg->fix_contact_forces_stress()->do_forward_comm();
}

template <>
void Granular<McHistoryModel>::compute_force(PairGran *pg, int eflag, int vflag, int addflag) {
    mc_pair_loop(lmp, cmodel, *aligned_sidata, *aligned_i_forces, *aligned_j_forces, pg, eflag, vflag, addflag);
}

template <>
void Granular<McNoHistoryModel>::compute_force(PairGran *pg, int eflag, int vflag, int addflag) {
    mc_pair_loop(lmp, cmodel, *aligned_sidata, *aligned_i_forces, *aligned_j_forces, pg, eflag, vflag, addflag);
}

}  // namespace PairStyles
}  // namespace LIGGGHTS

namespace {

template <typename T>
PairStyles::IGranularPairStyle *make_pair(LAMMPS *lmp, PairGran *parent, const int64_t hash) {
    return new T(lmp, parent, hash);
}

template <typename T>
Walls::IGranularWall *make_wall(LAMMPS *lmp, FixWallGran *parent, const int64_t hash) {
    return new T(lmp, parent, hash);
}

// One optimised instance per combination a deck may select; an unregistered combination would
// fall back to the library's runtime dispatch, which does not know mc_advanced.
template <int TANGENTIAL>
void register_combination() {
    typedef GranStyle<MC_ADVANCED, TANGENTIAL, COHESION_OFF, ROLLING_OFF, SURFACE_DEFAULT> Style;
    typedef ContactModel<Style> Model;
    PairStyles::Factory::instance().addStyle("gran", Style::HASHCODE, &make_pair<PairStyles::Granular<Model> >);
    Walls::Factory::instance().addStyle("gran", Style::HASHCODE, &make_wall<Walls::Granular<Model> >);
}

struct Registrar {
    Registrar() {
        ContactModels::Factory::instance().addNormalModel("mc_advanced", MC_ADVANCED);
        register_combination<TANGENTIAL_NO_HISTORY>();
        register_combination<TANGENTIAL_HISTORY>();
    }
};

Registrar registrar;

}  // namespace

// Entry point of `mcdem-liggghts`: the stock LIGGGHTS command line (-in, -var, -log, -echo, ...)
// with mc_advanced registered. Referencing this function from the executable also keeps the
// registrar's object file in the link.
extern "C" int mcdem_liggghts_main(int argc, char **argv) {
    // A run stopped by one rank (error->one: a contact out of range) ends in MPI_Abort, which
    // discards what stdio still buffers; with stdout going to a file or pipe the ERROR line itself
    // would be lost. Line buffering writes each line as it is completed (the screen output is a
    // few lines per thousand steps, so this costs nothing measurable).
    std::setvbuf(stdout, NULL, _IOLBF, 0);
    MPI_Init(&argc, &argv);
    LAMMPS_NS::LAMMPS *lmp = new LAMMPS_NS::LAMMPS(argc, argv, MPI_COMM_WORLD);
    lmp->input->file();
    delete lmp;
    MPI_Finalize();
    return 0;
}
