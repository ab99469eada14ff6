// The pair loop of `model mc_advanced` and the pair styles that use it (pair_loop.h).
#include "pair_batch.h"

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
