//! `fix ave/time`.

use crate::deck::*;

impl Deck {
    pub(in crate::deck) fn ave_time(&mut self, a: &[&str]) -> R<FixKind> {
        if a.len() < 8 {
            return Err("fix ave/time: expected Nevery Nrepeat Nfreq values…".into());
        }
        let (ne, nr, nf) = (int(a[4])? as u64, int(a[5])? as u64, int(a[6])? as u64);
        if ne == 0 || nr == 0 || nf == 0 || nf % ne != 0 || nr * ne > nf {
            return Err("fix ave/time: need Nfreq a multiple of Nevery and Nrepeat*Nevery <= Nfreq".into());
        }
        let mut values = Vec::new();
        let mut file = None;
        let mut k = 7;
        while k < a.len() {
            match a[k] {
                "file" => {
                    file = Some(a.get(k + 1).ok_or("ave/time file: missing name")?.to_string());
                    k += 2;
                }
                v if v.starts_with("c_") || v.starts_with("f_") || v.starts_with("v_") => {
                    values.push(v.to_string());
                    k += 1;
                }
                other => return Err(unsupported(&format!("fix ave/time keyword {other}"))),
            }
        }
        for v in &values {
            self.value_of(v, 0).map_err(|e| format!("fix ave/time value {v}: {e}"))?;
        }
        let out = match file {
            Some(f) => {
                let mut o = output::create(Path::new(&f))?;
                writeln!(o, "# Time-averaged data for fix {}\n# TimeStep {}", a[1], values.join(" "))
                    .map_err(|e| e.to_string())?;
                Some(o)
            }
            None => None,
        };
        let mut at = AveTime {
            name: a[1].into(),
            nevery: ne,
            nrepeat: nr,
            nfreq: nf,
            sum: vec![0.0; values.len()],
            last: vec![0.0; values.len()],
            values,
            irepeat: 0,
            nvalid: 0,
            out,
        };
        at.nvalid = at.next_valid(self.world.step);
        self.aves.push(Some(at));
        Ok(FixKind::AveTime(self.aves.len() - 1))
    }
}
