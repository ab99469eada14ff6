/*
 * NormalModel<MC_ADVANCED>'s set-up: the per-contact record, the keywords of the deck line, the
 * material table (validated by the core) and the checks that walls and pair agree.
 */
#include "normal_model.h"
#include "settings.h"

namespace mcdem_shim {

// `mprTest abs|signed` and the other keywords of settings.h are not on/off, yes/no or plain
// double keywords, the only ones Settings offers publicly: they go into its private table.
struct SettingsTableTag {
    typedef std::map<std::string, Setting *> Settings::*type;
    friend type private_member(SettingsTableTag);
};
template struct PrivateAccess<SettingsTableTag, &Settings::settings>;

}  // namespace mcdem_shim

namespace LIGGGHTS {
namespace ContactModels {

NormalModel<MC_ADVANCED>::NormalModel(LAMMPS *lmp, IContactHistorySetup *hsetup, ContactModelBase *c)
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

NormalModel<MC_ADVANCED>::~NormalModel() {
    std::map<LAMMPS *, NormalModel *>::iterator it = pair_models_.find(lmp);
    if (it != pair_models_.end() && it->second == this) pair_models_.erase(it);
    mcdem_influence_cache_free(cache_);
}

void NormalModel<MC_ADVANCED>::registerSettings(Settings &settings) {
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
    // The accuracy budget runs in `mcdem run` only (its per-particle references live in the Rust
    // engine's multi-contact pass, not in the C ABI the plugin calls).
    const char *budget = "the accuracy budget runs in `mcdem run` only; use geometryTolerance/updateEvery here";
    for (const char *key : {"mcAccuracy", "mcAccuracyCheck"})
        if (table.find(key) == table.end()) table[key] = new UnsupportedSetting(key, budget);
}

void NormalModel<MC_ADVANCED>::postSettings(IContactHistorySetup *, ContactModelBase *) {
    if (cmb_->is_wall()) return;
    pair_models_[lmp] = this;
    // Switches on the library's per-contact radius storage, read by the pair and wall loops
    // for detection, overlap and effective radius; it must be set before the pair's init.
    PairGran *pg = dynamic_cast<PairGran *>(force->pair);
    if (!pg) error->all(FLERR, "model mc_advanced: the pair style is not a granular pair style");
    pg->do_store_multicontact_data();
}

void NormalModel<MC_ADVANCED>::connectToProperties(PropertyRegistry &) {
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

// Stops a deck whose wall gives a shared setting (see SharedSetting) another value than the
// pair style's, instead of ignoring it.
void NormalModel<MC_ADVANCED>::check_wall_settings() const {
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

FixPropertyGlobal *NormalModel<MC_ADVANCED>::find_property(const char *name, const char *kind, int len, const char *usage) {
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
void NormalModel<MC_ADVANCED>::read_materials() {
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

void NormalModel<MC_ADVANCED>::fail_property(int type, const std::string &core_msg) {
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

std::map<LAMMPS *, NormalModel<MC_ADVANCED> *> NormalModel<MC_ADVANCED>::pair_models_;

}  // namespace ContactModels
}  // namespace LIGGGHTS
