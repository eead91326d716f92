//! The marcher's passes: the column pass (x transforms, windows) and the row pass (y transforms,
//! propagator, phase screen), and the checks of a recording.

use super::rows::{fast_tab_width, forward_row, inverse_row, par_rows, spectrum_to_ext};
use super::*;

impl Marcher {
    /// Scratch a row pass needs: the larger of the y FFTs' and the sine transform's.
    pub(super) fn row_scratch_len(&self) -> usize {
        self.row_inv
            .get_inplace_scratch_len()
            .max(self.row_fwd.get_inplace_scratch_len())
            .max(self.dst.as_ref().map_or(0, Dst::scratch_len))
    }

    /// Brings the field back to real space.
    pub(super) fn bring_to_real_space(&mut self) {
        if self.domain == Domain::Spectra {
            self.column_op(ColumnOp::Inverse(1.0 / self.spec.nx as f32));
            self.domain = Domain::YSpectra;
        }
        if self.domain == Domain::YSpectra {
            let ny = self.spec.ny;
            let (ground, ylen) = (self.spec.ground, self.spec.y_len());
            let inv = self.row_inv.clone();
            let dst = self.dst.as_ref();
            let scratch_len = self.row_scratch_len();
            let pool = &self.pool;
            let s = 1.0 / ylen as f32;
            self.field
                .par_chunks_mut(ny)
                .zip(self.nyquist.par_iter_mut())
                .for_each_init(
                    || pool.get(ylen, scratch_len),
                    |g, (row, nq)| {
                        let Scratch { a, b } = g.scratch();
                        inverse_row(ground, (&*inv, dst), row, *nq, &mut a[..ylen], b);
                        row.iter_mut().for_each(|z| *z *= s);
                    },
                );
            self.domain = Domain::Real;
        }
    }

    /// Builds the uniform path's propagator table for this screen, unless it holds it.
    pub(super) fn ensure_fast_tab(&mut self, screen: C32) {
        if self.fast_tab.as_ref().is_some_and(|(s, _)| *s == screen) {
            return;
        }
        let (nx, ny, ground) = (self.spec.nx, self.spec.ny, self.spec.ground);
        let tcols = self.ptab_cols;
        let width = fast_tab_width(ny, ground);
        let mut t = std::mem::take(&mut self.fast_tab)
            .map(|x| x.1)
            .unwrap_or_default();
        t.resize(tcols * width, C32::default());
        // ptab holds 1 / (nx ylen); the uniform path's x transforms carry their own 1 / nx.
        let scale = screen * nx as f32;
        let ptab = &self.ptab;
        t.par_chunks_mut(width).enumerate().for_each(|(kx, out)| {
            for (m, o) in out.iter_mut().enumerate() {
                let r = match ground {
                    Ground::None => m.min(ny - m),
                    _ => m,
                };
                *o = ptab[r * tcols + kx] * scale;
            }
        });
        self.fast_tab = Some((screen, t));
    }

    /// One uniform-medium step on the (kx, ky) spectra: per kx row, the propagator, the
    /// inverse y transform, the height window, the recorded rows (at kx), the forward y
    /// transform.
    pub(super) fn row_pass_uniform(&mut self, rec_rows: &[usize], rec: &mut [C32]) {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let (ground, ylen) = (self.spec.ground, self.spec.y_len());
        let width = fast_tab_width(ny, ground);
        let tab: &[C32] = &self.fast_tab.as_ref().expect("built by ensure_fast_tab").1;
        let wy = &self.window_y;
        let (inv, fwd) = (self.row_inv.clone(), self.row_fwd.clone());
        let dst = self.dst.as_ref();
        let scratch_len = self.row_scratch_len();
        let pool = &self.pool;
        let nr = rec_rows.len().max(1);
        par_rows(&mut self.field, &mut self.nyquist, rec, ny, nr).for_each_init(
            || pool.get(ylen, scratch_len),
            |g, (ix, ((row, nq), rec_row))| {
                let Scratch { a, b } = g.scratch();
                let (ext, scratch) = (&mut a[..ylen], b.as_mut_slice());
                let kx = ix.min(nx - ix);
                let trow = &tab[kx * width..(kx + 1) * width];
                row.iter_mut().zip(trow).for_each(|(z, p)| *z *= p);
                if width > ny {
                    *nq *= trow[ny];
                }
                inverse_row(ground, (&*inv, dst), row, *nq, ext, scratch);
                if !wy.is_empty() {
                    row.iter_mut().zip(wy).for_each(|(z, &w)| *z *= w);
                }
                for (r, &iy) in rec_rows.iter().enumerate() {
                    rec_row[r] = row[iy];
                }
                forward_row(ground, (&*fwd, dst), row, nq, ext, scratch);
            },
        );
    }

    pub(super) fn check_recording(&self, steps: usize, rec: &Recording<'_>) -> Result<()> {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let end = self.steps_done + steps;
        if let Some(&bad) = rec.record_rows.iter().find(|&&r| r >= ny) {
            return Err(CoreError::invalid(
                "record_rows",
                format!("must be within 0..{ny}"),
                bad,
            ));
        }
        if let Some((first, o)) = &rec.row_offsets {
            let (s, x) = o.dim();
            if *first > self.steps_done || first + s < end || x != nx {
                return Err(CoreError::invalid(
                    "row_offsets",
                    format!(
                        "must cover steps {}..{end} with {nx} columns",
                        self.steps_done
                    ),
                    format!("{:?} from step {first}", o.dim()),
                ));
            }
            let (lo, hi) = rec
                .record_rows
                .iter()
                .fold((usize::MAX, 0), |(a, b), &r| (a.min(r), b.max(r)));
            let bad = o
                .iter()
                .any(|&v| (lo as i64 + v) < 0 || (hi as i64 + v) >= ny as i64);
            if !rec.record_rows.is_empty() && bad {
                return Err(CoreError::invalid(
                    "row_offsets",
                    format!("must keep the recorded rows within 0..{ny}"),
                    "a row outside the grid",
                ));
            }
        }
        if let Some(rows) = &rec.rows {
            let (r, s, x) = rows.dim();
            if r != rec.record_rows.len() || s < end || x != nx {
                return Err(CoreError::invalid(
                    "rows",
                    format!(
                        "output must have shape ({}, >= {end}, {nx})",
                        rec.record_rows.len()
                    ),
                    format!("{:?}", rows.dim()),
                ));
            }
        }
        if let Some((col, out)) = &rec.column {
            if *col >= nx {
                return Err(CoreError::invalid(
                    "record_column",
                    format!("must be within 0..{nx}"),
                    col,
                ));
            }
            let (s, y) = out.dim();
            if s < end || y != ny {
                return Err(CoreError::invalid(
                    "column",
                    format!("output must have shape (>= {end}, {ny})"),
                    format!("{:?}", out.dim()),
                ));
            }
        }
        Ok(())
    }

    /// The real-space values of row `ix` while the field is held as y-spectra, in
    /// `self.col_buf[..ny]` (reused across steps).
    pub(super) fn real_row(&mut self, ix: usize) -> &[C32] {
        let ny = self.spec.ny;
        let ylen = self.spec.y_len();
        // The sine transform's work space and FFT scratch sit after the row (sized once).
        let extra = self.dst.as_ref().map_or(0, Dst::scratch_len);
        self.col_buf.resize(ylen + extra, C32::default());
        let row = &self.field[ix * ny..(ix + 1) * ny];
        if let Some(dst) = &self.dst {
            let (out, rest) = self.col_buf.split_at_mut(ny);
            let (y, scratch) = rest.split_at_mut(ny);
            out.copy_from_slice(row);
            dst.apply(out, y, scratch, Dst::INVERSE);
        } else {
            let ext = &mut self.col_buf[..ylen];
            spectrum_to_ext(self.spec.ground, row, self.nyquist[ix], ext);
            self.row_inv.process(ext);
        }
        let s = 1.0 / ylen as f32;
        self.col_buf[..ny].iter_mut().for_each(|z| *z *= s);
        &self.col_buf[..ny]
    }

    /// Forward y transform of every row (real space -> y-spectra).
    pub(super) fn forward_rows(&mut self) {
        let ny = self.spec.ny;
        let ground = self.spec.ground;
        let fft = self.row_fwd.clone();
        let dst = self.dst.as_ref();
        let ylen = self.spec.y_len();
        let scratch_len = fft
            .get_inplace_scratch_len()
            .max(dst.map_or(0, Dst::scratch_len));
        self.field
            .par_chunks_mut(ny)
            .zip(self.nyquist.par_iter_mut())
            .for_each_init(
                || self.pool.get(ylen, scratch_len),
                |g, (row, nq)| {
                    let s = g.scratch();
                    forward_row(ground, (&*fft, dst), row, nq, &mut s.a[..ylen], &mut s.b)
                },
            );
        self.domain = Domain::YSpectra;
    }

    /// x transforms, propagator and inverse x transforms, block by block of columns (the
    /// uniform screen, if any, folded into the propagator).
    pub(super) fn column_pass(&mut self, uniform_screen: Option<C32>) {
        let one = C32::new(1.0, 0.0);
        let scaled = match uniform_screen {
            Some(sc) if sc != one => {
                if self.scaled.as_ref().is_none_or(|(old, _)| *old != sc) {
                    let mut t = std::mem::take(&mut self.scaled)
                        .map(|x| x.1)
                        .unwrap_or_default();
                    t.clear();
                    t.extend(self.ptab.iter().map(|p| p * sc));
                    self.scaled = Some((sc, t));
                }
                true
            }
            _ => false,
        };
        self.column_op(ColumnOp::Propagate { scaled });
    }

    /// One [`ColumnOp`] on every column of the y-spectra (and the `"pec-v"` Nyquist row),
    /// block by block of `COLUMN_BLOCK` columns gathered into contiguous scratch.
    #[allow(unsafe_code)]
    // Long: the columns' gather into scratch, both FFTs and the operation share one unsafe block
    // and its buffers; one function keeps the unsafe code in one place.
    pub(super) fn column_op(&mut self, op: ColumnOp) {
        let ptab: &[C32] = match op {
            ColumnOp::Propagate { scaled: true } => {
                &self.scaled.as_ref().expect("set by column_pass").1
            }
            _ => &self.ptab,
        };
        let wxm: &[f32] = &self.window_xm;
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let ground = self.spec.ground;
        let fwd = self.col_fwd.clone();
        let inv = self.col_inv.clone();
        let scratch_len = fwd
            .get_inplace_scratch_len()
            .max(inv.get_inplace_scratch_len());
        let tcols = self.ptab_cols;
        let ky_row = |m: usize| match ground {
            Ground::None => m.min(ny - m),
            _ => m,
        };
        let half = nx / 2;
        // Does `op` to `buf` (whole columns, the first at spectral column m0); rustfft
        // batches the columns in one call each way.
        let apply = |buf: &mut [C32], m0: usize, scratch: &mut [C32]| match op {
            ColumnOp::Propagate { .. } => {
                fwd.process_with_scratch(buf, scratch);
                for (j, col) in buf.chunks_exact_mut(nx).enumerate() {
                    let m = ky_row(m0 + j);
                    let prow = &ptab[m * tcols..(m + 1) * tcols];
                    // P depends on |kx|: ix <= nx/2 reads prow forwards, the rest backwards.
                    let (lo, hi) = col.split_at_mut(half + 1);
                    lo.iter_mut().zip(prow).for_each(|(z, p)| *z *= p);
                    hi.iter_mut()
                        .zip(prow[1..half + nx % 2].iter().rev())
                        .for_each(|(z, p)| *z *= p);
                }
                inv.process_with_scratch(buf, scratch);
            }
            ColumnOp::Forward => fwd.process_with_scratch(buf, scratch),
            ColumnOp::Inverse(s) => {
                inv.process_with_scratch(buf, scratch);
                buf.iter_mut().for_each(|z| *z *= s);
            }
            ColumnOp::Window => {
                inv.process_with_scratch(buf, scratch);
                for col in buf.chunks_exact_mut(nx) {
                    col.iter_mut().zip(wxm).for_each(|(z, &w)| *z *= w);
                }
                fwd.process_with_scratch(buf, scratch);
            }
        };
        let ptr = FieldPtr(self.field.as_mut_ptr());
        let blocks = ny.div_ceil(COLUMN_BLOCK);
        let pool = &self.pool;
        (0..blocks).into_par_iter().for_each_init(
            || pool.get(COLUMN_BLOCK * nx, scratch_len),
            |g, block| {
                let Scratch { a: buf, b } = g.scratch();
                let scratch = b.as_mut_slice();
                let m0 = block * COLUMN_BLOCK;
                let w = COLUMN_BLOCK.min(ny - m0);
                let base = ptr.get();
                // SAFETY (both loops): this task alone touches columns m0..m0+w of the
                // nx * ny field (blocks are disjoint), every index is < nx * ny, and no
                // reference to the field exists while the pass runs (we hold &mut self).
                // Gather as 8 x 8 tiles: 8 contiguous reads of a row, 8 contiguous writes of a
                // column, so both sides stream whole cache lines.
                let mut tile = [[C32::default(); COLUMN_BLOCK]; 8];
                let mut ix0 = 0;
                while ix0 < nx {
                    let h = 8.min(nx - ix0);
                    for r in 0..h {
                        for j in 0..w {
                            tile[r][j] = unsafe { base.add((ix0 + r) * ny + m0 + j).read() };
                        }
                    }
                    for j in 0..w {
                        for r in 0..h {
                            buf[j * nx + ix0 + r] = tile[r][j];
                        }
                    }
                    ix0 += h;
                }
                apply(&mut buf[..w * nx], m0, scratch);
                let mut ix0 = 0;
                while ix0 < nx {
                    let h = 8.min(nx - ix0);
                    for j in 0..w {
                        for r in 0..h {
                            tile[r][j] = buf[j * nx + ix0 + r];
                        }
                    }
                    for r in 0..h {
                        for j in 0..w {
                            unsafe { base.add((ix0 + r) * ny + m0 + j).write(tile[r][j]) };
                        }
                    }
                    ix0 += h;
                }
            },
        );
        if ground == Ground::PecV {
            let mut scratch = vec![C32::default(); scratch_len];
            let mut col = std::mem::take(&mut self.nyquist);
            apply(&mut col, ny, &mut scratch);
            self.nyquist = col;
        }
    }

    /// Inverse y transform of every row, then screen, window, obstacles and recording;
    /// then (if `forward_again`) the forward y transform for the next step.
    // Long: the inverse transform, screen, window, obstacles, recording and the forward transform
    // of a row share the row's scratch in one pass.
    pub(super) fn row_pass(
        &mut self,
        medium: &StepMedium<'_>,
        obstacle: &StepObstacle<'_>,
        record: (&[usize], Option<ndarray::ArrayView1<'_, i64>>, &mut [C32]),
        forward_again: bool,
    ) {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let ground = self.spec.ground;
        let ylen = self.spec.y_len();
        let half_k0_dz = 0.5 * wavenumber(self.spec.freq_hz) * self.spec.dz_m;
        // A uniform screen was folded into P by the column pass.
        let uniform = match medium {
            StepMedium::Uniform(_) => Some(C32::new(1.0, 0.0)),
            _ => None,
        };
        let fixed = self.fixed_screen.as_deref();
        let (wx, wy) = (&self.window_x, &self.window_y);
        let dy = self.spec.dy_m;
        let inv = self.row_inv.clone();
        let fwd = self.row_fwd.clone();
        let dst = self.dst.as_ref();
        let scratch_len = self.row_scratch_len();
        let (rec_rows, offsets, rec) = record;
        let nr = rec_rows.len().max(1);
        debug_assert_eq!(rec.len(), nx * nr);
        let pool = &self.pool;
        par_rows(&mut self.field, &mut self.nyquist, rec, ny, nr).for_each_init(
            || pool.get(ylen, scratch_len),
            |g, (ix, ((row, nq), rec_row))| {
                let Scratch { a, b } = g.scratch();
                let (ext, scratch) = (&mut a[..ylen], b.as_mut_slice());
                inverse_row(ground, (&*inv, dst), row, *nq, ext, scratch);
                match (uniform, medium) {
                    (Some(s), _) if s != C32::new(1.0, 0.0) => {
                        row.iter_mut().for_each(|z| *z *= s);
                    }
                    (None, StepMedium::Fixed) => {
                        let scr = &fixed.expect("checked in advance")[ix * ny..(ix + 1) * ny];
                        row.iter_mut().zip(scr).for_each(|(z, s)| *z *= s);
                    }
                    (None, StepMedium::CrossRange(n)) => {
                        let f = to_c32(screen_factor(n[ix], half_k0_dz));
                        row.iter_mut().for_each(|z| *z *= f);
                    }
                    (None, StepMedium::Index(n)) => {
                        row.iter_mut().zip(n.row(ix)).for_each(|(z, &nn)| {
                            *z *= to_c32(screen_factor(nn, half_k0_dz));
                        });
                    }
                    _ => {}
                }
                if !wx.is_empty() {
                    let a = wx[ix];
                    row.iter_mut().zip(wy).for_each(|(z, &b)| *z *= a * b);
                }
                match obstacle {
                    StepObstacle::None => {}
                    StepObstacle::Mask(mask) => {
                        row.iter_mut().zip(mask.row(ix)).for_each(|(z, &blocked)| {
                            if blocked {
                                *z = C32::default();
                            }
                        });
                    }
                    StepObstacle::Heights(h) => {
                        let hh = h[ix];
                        if hh >= 0.0 {
                            let top = ((hh / dy).floor() as usize).min(ny - 1);
                            row[..=top].iter_mut().for_each(|z| *z = C32::default());
                        }
                    }
                }
                let shift = offsets.map_or(0, |o| o[ix]);
                for (r, &iy) in rec_rows.iter().enumerate() {
                    let at = (iy as i64 + shift).clamp(0, ny as i64 - 1) as usize;
                    rec_row[r] = row[at];
                }
                if forward_again {
                    forward_row(ground, (&*fwd, dst), row, nq, ext, scratch);
                }
            },
        );
    }
}
