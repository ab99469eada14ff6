/*
 * The multi-contact bookkeeping of NormalModel<MC_ADVANCED> (see shim.h): per force pass, every
 * contact of each owned particle with its point and last force, the core's radius changes, and
 * those changes where the pair and wall loops read them.
 */
#include "normal_model.h"

namespace mcdem_shim {

// The private-access idiom (shim.h) for the per-atom row pointers of a contact store (FixContactHistory's protected
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

}  // namespace mcdem_shim

namespace LIGGGHTS {
namespace ContactModels {

void NormalModel<MC_ADVANCED>::collect_sources() {
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

void NormalModel<MC_ADVANCED>::update_radius_changes() {
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

NormalModel<MC_ADVANCED>::PairRecords NormalModel<MC_ADVANCED>::pair_records() {
    const NeighList *list = static_cast<PairGranProxy *>(sources_[0].history.get_ptr())->list;
    PairRecords pr = {list, sources_[0].store, list->listgranhistory->firstdouble, list->listgranhistory->dnum,
                      record_offset_};
    return pr;
}

// Step 1 for the pair source (sources_[0]): its records are the contact histories of the
// neighbour-list entries, read in place (what HistoryData's accessors do, without a call and a
// type switch per record). The contact points still come from the library's compute_surfPos.
void NormalModel<MC_ADVANCED>::gather_pair_records(int i, double f_eps) {
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
void NormalModel<MC_ADVANCED>::copy_to_pair_records() {
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

void NormalModel<MC_ADVANCED>::write_pair_radius_changes(double *rec, bool i_first, double dri, double drj) {
    rec[kPairDrLo] = i_first ? dri : drj;
    rec[kPairDrHi] = i_first ? drj : dri;
}

// Empties a wall store's rows for this step (see McSource). Mesh walls keep the library's rows:
// their number per particle, the triangles near it, is what the wall loop searches. A primitive
// wall's rows are pointed at one row per particle (owned and ghost) owned here; the library
// points them back at its own storage at the next neighbour-list build, before they are used.
void NormalModel<MC_ADVANCED>::empty_wall_rows(McSource &src) {
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

}  // namespace ContactModels
}  // namespace LIGGGHTS
