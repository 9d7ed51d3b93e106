//! A split increment on the GPU executor: the increment's entries before the split run by the
//! CPU twin, every role the increment writes read back into it before and written back after,
//! the rest recorded here (`Contact::run_split`).

use super::*;

impl GpuExec {
    /// [`IncrementExec::run_split`] on this executor.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn split(
        &mut self,
        positions: &wgpu::Buffer,
        velocities: &wgpu::Buffer,
        forces: &wgpu::Buffer,
        inc: &Increment<'_>,
        first_gpu: usize,
        twin: &mut crate::contact::exec::cpu::CpuExec,
    ) -> Result<usize> {
        for (what, b, usage) in [
            ("device positions", positions, wgpu::BufferUsages::COPY_SRC),
            (
                "device velocities",
                velocities,
                wgpu::BufferUsages::COPY_SRC,
            ),
            (
                "device forces",
                forces,
                wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
        ] {
            if !b.usage().contains(usage) {
                return Err(Error::BadParameter {
                    name: what,
                    value: format!("usage {:?}", b.usage()),
                    expected: "COPY_SRC (and COPY_DST for forces): a split increment reads the \
                               caller's buffers back and writes the forces",
                });
            }
        }
        let max_dim = self.prepare(Positions::Shared(positions), velocities, forces, inc)?;
        let entries = self.entries(inc)?;
        let k = first_gpu.min(entries.len());
        let ctx = self.ctx.clone();
        // every role the increment writes, read back into the twin, with the caller's arrays
        let n4 = self.n_nodes * 16;
        let mut roles: Vec<(Option<usize>, Buf)> = Vec::new();
        for &(buf, per_pair) in &crate::contact::exec::HANDED_OVER {
            if per_pair {
                roles.extend((0..self.pairs.len()).map(|p| (Some(p), buf)));
            } else if buf != Buf::HostForces {
                roles.push((None, buf));
            }
        }
        let mut sources: Vec<(&wgpu::Buffer, u64, u64)> = vec![(positions, 0, n4 as u64)];
        sources.extend([(velocities, 0, n4 as u64), (forces, 0, n4 as u64)]);
        for &(pair, buf) in &roles {
            let setup = &inc.pairs[pair.unwrap_or(0)].setup;
            let len = twin.role_bytes(pair, buf, setup).map_or(0, |b| b.len());
            let gpu = self
                .role_buffer(pair, buf, forces)
                .ok_or_else(|| missing_role(buf))?;
            sources.push((gpu, GpuSearch::role_offset(buf), len as u64));
        }
        let bytes = crate::gpu::buffers::copy_back(&ctx, &sources, "split increment readback")?;
        let mut host: Vec<Vec<[f32; 4]>> = (0..3)
            .map(|i| bytemuck::pod_collect_to_vec(&bytes[i * n4..(i + 1) * n4]))
            .collect();
        let mut at = 3 * n4;
        for &(pair, buf) in &roles {
            let setup = &inc.pairs[pair.unwrap_or(0)].setup;
            if let Some(dst) = twin.role_bytes(pair, buf, setup) {
                dst.copy_from_slice(&bytes[at..at + dst.len()]);
                at += dst.len();
            }
        }
        // the twin: the resets the GPU's copies do, then the entries before the split
        let mut f = host.pop().unwrap_or_default();
        twin.reset()?;
        twin.run_entries(&entries[..k], &[&host[0]], &host[1], &mut f, inc)?;
        // everything written back, and the rest of the increment here
        for &(pair, buf) in &roles {
            let setup = &inc.pairs[pair.unwrap_or(0)].setup;
            let gpu = self
                .role_buffer(pair, buf, forces)
                .ok_or_else(|| missing_role(buf))?;
            if let Some(src) = twin.role_bytes(pair, buf, setup) {
                if !src.is_empty() {
                    crate::gpu::upload(&ctx, gpu, GpuSearch::role_offset(buf), src);
                }
            }
        }
        crate::gpu::upload(&ctx, forces, 0, bytemuck::cast_slice(&f));
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("split increment"),
            });
        self.record_entries(&mut enc, &entries[k..], max_dim)?;
        self.inc()?.end(&mut enc);
        crate::device::submit(&ctx, enc);
        self.inc()?.take_uncaptured()?;
        Ok(entries.len())
    }

    /// The GPU buffer of role `buf` of pair `pair` (`None`: the increment's own, or the
    /// caller's forces).
    fn role_buffer<'a>(
        &'a self,
        pair: Option<usize>,
        buf: Buf,
        forces: &'a wgpu::Buffer,
    ) -> Option<&'a wgpu::Buffer> {
        match pair {
            Some(k) => {
                let p = self.pairs.get(k)?;
                p.search
                    .role_buffer(buf)
                    .or_else(|| p.penalty.role_buffer(buf))
            }
            None if buf == Buf::HostForces => Some(forces),
            None => self.inc.as_deref()?.role_buffer(buf),
        }
    }
}

/// The error of a role no executor buffer holds (a bug: `HANDED_OVER` and the executors
/// disagree).
fn missing_role(buf: Buf) -> Error {
    Error::Gpu {
        during: "a split increment".into(),
        message: format!("no buffer holds {buf:?}"),
    }
}
