/*
 * NormalModel<MC_ADVANCED>: the normal force of one contact and the per-contact record, inline
 * here because the pair and wall loops call them per contact. Its set-up (settings, materials,
 * walls) is in normal_model_setup.cpp, its multi-contact bookkeeping in bookkeeping.cpp.
 */
#ifndef MCDEM_SHIM_NORMAL_MODEL_H
#define MCDEM_SHIM_NORMAL_MODEL_H

#include "shim.h"

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
    // Adds the per-contact record to the contact history (normal_model_setup.cpp).
    NormalModel(LAMMPS *lmp, IContactHistorySetup *hsetup, ContactModelBase *c);
    ~NormalModel();

    // The model's keywords, materials and the walls' stores (normal_model_setup.cpp).
    void registerSettings(Settings &settings);
    void postSettings(IContactHistorySetup *, ContactModelBase *);
    void connectToProperties(PropertyRegistry &);

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
    // radius sum but leaves radi at the original radius (its walls grow radi). docs/spec.md §2 uses the
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
    // Set-up (normal_model_setup.cpp).
    // Stops a deck whose wall gives a shared setting (see SharedSetting) another value than the
    // pair style's, instead of ignoring it.
    void check_wall_settings() const;
    FixPropertyGlobal *find_property(const char *name, const char *kind, int len, const char *usage);
    // Reads the material per atom type, validates it through the core and builds the pair
    // coefficient table (one entry per type pair, walls have their own atom type).
    void read_materials();

    // The radius changes of every contact, once per force pass (bookkeeping.cpp).
    void collect_sources();
    void update_radius_changes();
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
    PairRecords pair_records();
    void gather_pair_records(int i, double f_eps);
    void copy_to_pair_records();
    static void write_pair_radius_changes(double *rec, bool i_first, double dri, double drj);
    void empty_wall_rows(McSource &src);

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
    // The settings as the library's table reads them (MCDEM_SETTING_* order; the typed fields
    // above are set from them once parsed) and which of them this model's deck line gave.
    double settings_[MCDEM_SETTINGS];
    bool given_[MCDEM_SETTINGS];
    // The pair style's model of each LIGGGHTS instance (set when its settings are parsed), whose
    // shared settings apply to the instance's walls. Keyed by instance: a program may open several.
    static std::map<LAMMPS *, NormalModel *> pair_models_;
};

}  // namespace ContactModels
}  // namespace LIGGGHTS

#endif
