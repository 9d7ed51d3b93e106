//! The direct-submit search: one submit per search, its status words and hits read back at once
//! (`GlobalSearch::run` and `step`, kinematic pairs, point queries, the anchoring search), and a
//! search whose first steps ran on the CPU mirror finished here (`run_split`).

use super::*;

impl GpuSearch {
    /// Runs a global search. Returns the hits.
    pub fn run(&mut self, prep: &Prepared) -> Result<Arc<Vec<GpuHit>>> {
        Ok(self.run_with(prep, 0, None, true, false)?.0)
    }

    /// Runs a global search (`local` false) or the motion check and the local search, in one
    /// submit. Returns the hits (empty unless `read_hits`) and the status words.
    pub(crate) fn run_mode(
        &mut self,
        prep: &Prepared,
        local: bool,
        read_hits: bool,
    ) -> Result<(Arc<Vec<GpuHit>>, [u32; STATUS_WORDS])> {
        if local && !self.searched {
            return Err(Error::BadParameter {
                name: "local search",
                value: "before any global search".into(),
                expected: "a global search first",
            });
        }
        self.run_with(prep, 0, None, read_hits, local)
    }

    /// Runs the steps `STEPS[first..]` on the GPU, starting from the CPU mirror's state after
    /// `STEPS[..first]` (`preload`: the bytes of each role those steps wrote, by `Buf`): the
    /// GPU half of a split run,
    /// which finds the first step where the two executors diverge.
    pub fn run_split(
        &mut self,
        prep: &Prepared,
        first: usize,
        preload: &[(Buf, &[u8])],
    ) -> Result<(Arc<Vec<GpuHit>>, [u32; STATUS_WORDS])> {
        self.run_with(prep, first, Some(preload), true, false)
    }

    /// Runs the search steps `STEPS[first..]` (or the local search) in one command encoder and
    /// submit, reading back once. Returns the hits (empty unless `read_hits`) and the status
    /// words.
    pub(crate) fn run_with(
        &mut self,
        prep: &Prepared,
        first: usize,
        preload: Option<&[(Buf, &[u8])]>,
        read_hits: bool,
        local: bool,
    ) -> Result<(Arc<Vec<GpuHit>>, [u32; STATUS_WORDS])> {
        self.ensure_buffers(prep)?;
        if let Some(src) = self.device_positions.clone() {
            let need = prep.n_nodes as u64 * 16;
            if src.size() < need || !src.usage().contains(U::STORAGE) {
                return Err(Error::BadParameter {
                    name: "device positions",
                    value: format!("buffer of {} bytes, usage {:?}", src.size(), src.usage()),
                    expected: "needs one vec4<f32> per model node and STORAGE usage",
                });
            }
            let frame = FrameParams {
                origin: [
                    prep.grid.frame[0] as f32,
                    prep.grid.frame[1] as f32,
                    prep.grid.frame[2] as f32,
                    0.0,
                ],
                n_nodes: prep.n_nodes as u32,
                _pad: [0; 3],
            };
            crate::gpu::upload(&self.ctx, &self.frame, 0, bytemuck::bytes_of(&frame));
        }
        if self.device_positions.is_none() {
            crate::gpu::upload(
                &self.ctx,
                &self.buffers.nodes.buffer,
                0,
                bytemuck::cast_slice(&prep.nodes),
            );
        }
        self.upload_static(prep);
        for (i, tp) in tree_passes(prep.params.tree_levels).iter().enumerate() {
            crate::gpu::upload(
                &self.ctx,
                &self.buffers.tree_params.buffer,
                i as u64 * UNIFORM_STRIDE,
                bytemuck::bytes_of(tp),
            );
        }
        let work = work_levels(prep);
        for i in 0..work.levels.len() {
            crate::gpu::upload(
                &self.ctx,
                &self.buffers.work_scan_params.buffer,
                i as u64 * UNIFORM_STRIDE,
                bytemuck::bytes_of(&work.params(i)),
            );
        }
        for &(buf, bytes) in preload.unwrap_or(&[]) {
            let target = self.role_buffer(buf).ok_or_else(|| Error::Gpu {
                during: "a split search".into(),
                message: format!("no buffer holds {buf:?}"),
            })?;
            crate::gpu::upload(&self.ctx, target, 0, bytes);
        }
        if self.bind_groups.is_none() {
            self.bind_groups = Some(self.bind_groups(prep)?);
            self.tree_levels = Some(prep.params.tree_levels);
            self.work_levels = work_levels(prep).levels.len();
            self.generation += 1;
        }
        if let Some(src) = self.device_positions.clone() {
            let fresh = matches!(&self.to_local_group, Some((b, g, _)) if *b == src && *g == self.generation);
            if !fresh {
                let group = crate::gpu::bind(
                    &self.ctx.device,
                    &self.pipelines.to_local,
                    &passes::TO_LOCAL,
                    |buf| match buf {
                        Buf::Positions => Some(src.as_entire_binding()),
                        other => self.resource(other),
                    },
                )?;
                self.to_local_group = Some((src, self.generation, group));
            }
        }
        crate::gpu::upload(
            &self.ctx,
            &self.buffers.params,
            0,
            bytemuck::bytes_of(&prep.params),
        );
        if !read_hits {
            let status = self.submit(&prep.params, prep, first, false, &mut Vec::new(), local)?;
            return Ok((Arc::default(), status));
        }
        let mut hits = std::mem::take(&mut self.hits_cache);
        if Arc::get_mut(&mut hits).is_none() {
            hits = Arc::default(); // the last result is still held: a fresh allocation
        }
        let out = Arc::get_mut(&mut hits).expect("unique");
        let status = self.submit(&prep.params, prep, first, true, out, local)?;
        if !local {
            self.searched = true;
        }
        self.hits_cache = hits.clone();
        Ok((hits, status))
    }

    /// Encodes the steps `STEPS[first..]`, submits once and reads back the status words and,
    /// when `read_hits`, the hits into `hits` (resized to one per slave).
    pub(super) fn submit(
        &self,
        params: &SearchParams,
        prep: &Prepared,
        first: usize,
        read_hits: bool,
        hits: &mut Vec<GpuHit>,
        local: bool,
    ) -> Result<[u32; STATUS_WORDS]> {
        let n_slaves = prep.slaves.len();
        let (device, b, p) = (&self.ctx.device, &self.buffers, &self.pipelines);
        let bg = self
            .bind_groups
            .as_ref()
            .expect("bind groups built before submit");
        let max_dim = self.max_workgroups_per_dim;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("global search"),
        });
        if first == 0 {
            reset_status(&mut enc, &b.status_reset, &b.status, Owner::Search);
        }
        let dispatch = |enc: &mut wgpu::CommandEncoder,
                        group: &'static groups::Group,
                        work: &[crate::gpu::Work<'_>]| {
            crate::gpu::run_pass(&self.ctx, enc, group, work, max_dim)
        };
        if let Some((_, _, group)) = &self.to_local_group {
            if self.device_positions.is_some() {
                dispatch(
                    &mut enc,
                    &groups::DIRECT_TO_LOCAL,
                    &[(&p.to_local, group, prep.n_nodes as u32, ITEM_WORKGROUP)],
                );
            }
        }
        let steps: &[Step] = if local { &[] } else { &STEPS[first..] };
        if local && self.anchored {
            dispatch(
                &mut enc,
                &groups::DIRECT_ANCHOR,
                &[(&p.anchor, &bg.anchor, params.n_slaves, ITEM_WORKGROUP)],
            );
        } else if local {
            dispatch(
                &mut enc,
                &groups::DIRECT_LOCAL,
                &[
                    (
                        &p.motion,
                        &bg.motion,
                        prep.motion_nodes.len() as u32,
                        ITEM_WORKGROUP,
                    ),
                    (
                        &p.local_search,
                        &bg.local_search,
                        params.n_slaves,
                        ITEM_WORKGROUP,
                    ),
                ],
            );
        }
        for step in steps {
            match step {
                Step::TreeRefit => {
                    let passes = tree_passes(params.tree_levels);
                    let work: Vec<crate::gpu::Work<'_>> = passes
                        .iter()
                        .zip(&bg.tree_refit)
                        .map(|(tp, g)| (&p.tree_refit, g, 1u32 << tp.bottom, TREE_WORKGROUP))
                        .collect();
                    dispatch(&mut enc, &groups::DIRECT_TREE_REFIT, &work);
                }
                Step::NearestFacet => {
                    let work = work_levels(prep);
                    let mut seq = vec![
                        (
                            &p.walk_start,
                            &bg.walk_start,
                            params.n_slaves.div_ceil(crate::abi::search::WALK_GROUP),
                            ITEM_WORKGROUP,
                        ),
                        (
                            &p.nearest_walk,
                            &bg.nearest_walk,
                            params.n_slaves,
                            ITEM_WORKGROUP,
                        ),
                    ];
                    scan_work(p, &work, &bg.work_scan_blocks, &bg.work_scan_add, &mut seq);
                    seq.push((&p.nearest_args, &bg.nearest_args, 1, 1));
                    dispatch(&mut enc, &groups::DIRECT_WALK_SCAN, &seq);
                    let chunks = [
                        (&p.nearest_chunks, &bg.nearest_chunks, 0),
                        (&p.nearest_ties, &bg.nearest_ties, 0),
                    ];
                    crate::gpu::run_indirect_pass(
                        &self.ctx,
                        &mut enc,
                        &groups::DIRECT_CHUNKS,
                        &chunks,
                        &b.args,
                    );
                    let mut last = Vec::new();
                    if params.flags & crate::abi::search::FLAG_SELF_CONTACT != 0 {
                        last.push((
                            &p.nearest_crowded,
                            &bg.nearest_crowded,
                            params.n_slaves,
                            ITEM_WORKGROUP,
                        ));
                    }
                    last.push((
                        &p.nearest_facet,
                        &bg.nearest_facet,
                        params.n_slaves,
                        ITEM_WORKGROUP,
                    ));
                    dispatch(&mut enc, &groups::DIRECT_NEAREST, &last);
                }
            }
        }
        if !local && first < STEPS.len() {
            // the frame of this global search is the reference of the motion budget
            enc.copy_buffer_to_buffer(
                &b.nodes.buffer,
                0,
                &b.reference.buffer,
                0,
                (prep.n_nodes * 16) as u64,
            );
        }
        let hits_bytes = if read_hits {
            (n_slaves * std::mem::size_of::<GpuHit>()) as u64
        } else {
            0
        };
        enc.copy_buffer_to_buffer(&b.status, 0, &b.readback.buffer, 0, STATUS_BYTES);
        if hits_bytes > 0 {
            enc.copy_buffer_to_buffer(
                &b.hits.buffer,
                0,
                &b.readback.buffer,
                READBACK_HITS_OFFSET,
                hits_bytes,
            );
        }
        crate::device::submit(&self.ctx, enc);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu {
                during: "contact increment".into(),
                message: e.to_string(),
            });
        }
        let status = read_back_with(
            &self.ctx,
            &b.readback.buffer,
            READBACK_HITS_OFFSET + hits_bytes,
            "global search readback",
            |bytes| {
                let status: [u32; STATUS_WORDS] =
                    bytemuck::pod_read_unaligned(&bytes[..STATUS_BYTES as usize]);
                let raw = &bytes[READBACK_HITS_OFFSET as usize..];
                hits.resize(
                    raw.len() / std::mem::size_of::<GpuHit>(),
                    bytemuck::Zeroable::zeroed(),
                );
                bytemuck::cast_slice_mut::<GpuHit, u8>(hits).copy_from_slice(raw);
                status
            },
        )?;
        self.ctx.take_uncaptured("contact increment")?;
        Ok(status)
    }

    /// Reads the caller's positions buffer back as f64 (the rare refit of a device-positions
    /// increment).
    pub fn read_positions(&self, buffer: &wgpu::Buffer, n_nodes: usize) -> Result<Vec<[f64; 3]>> {
        if !buffer.usage().contains(U::COPY_SRC) {
            return Err(Error::BadParameter {
                name: "device positions",
                value: format!("usage {:?}", buffer.usage()),
                expected: "COPY_SRC, so the grid can be refitted",
            });
        }
        let d = &self.ctx.device;
        let bytes = n_nodes as u64 * 16;
        let staging = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("positions readback"),
            size: bytes.max(16),
            usage: U::MAP_READ | U::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("positions readback"),
        });
        enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
        crate::device::submit(&self.ctx, enc);
        let raw = read_back(&self.ctx, &staging, bytes, "positions readback")?;
        let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&raw);
        Ok(v.iter()
            .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
            .collect())
    }
}
