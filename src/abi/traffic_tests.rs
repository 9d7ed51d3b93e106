//! Tests of the declared traffic (`abi::traffic`).

use super::*;
use crate::abi::passes::Access;

/// Every declared record lives in one of the pass's bindings, a written one in a binding the
/// shader may write, and every storage binding but the status and statistics words is declared (a binding
/// added to a pass without its traffic fails here).
#[test]
fn declarations_follow_the_bindings() {
    for pass in DECLARED {
        let touches = touches(pass).unwrap();
        for t in touches {
            let b = pass
                .bindings
                .iter()
                .find(|b| b.buf == t.buf)
                .unwrap_or_else(|| panic!("{}: {:?} is not bound", pass.entry, t.buf));
            assert!(t.dir == Dir::Read || b.access == Access::ReadWrite);
            assert_ne!(
                b.access,
                Access::Uniform,
                "{}: uniforms are not counted",
                pass.entry
            );
            let slave_only = matches!(
                t.of,
                Of::Slave
                    | Of::NearSlave
                    | Of::FarSlave
                    | Of::NearOrMaster
                    | Of::Near
                    | Of::Crossing
                    | Of::Walking
            );
            assert!(
                !slave_only || pass.items != Items::One,
                "{}: a one-invocation pass has no slave items",
                pass.entry
            );
        }
        if pass.items == Items::One {
            continue;
        }
        for b in pass.bindings {
            if b.access == Access::Uniform || matches!(b.buf, Buf::Status | Buf::Stats) {
                continue;
            }
            assert!(
                touches.iter().any(|t| t.buf == b.buf),
                "{}: binding {:?} has no declared traffic",
                pass.entry,
                b.buf
            );
        }
    }
}

/// A slave beyond the radius costs the passes over the active slaves nothing, and a pass
/// over every slave the records it reads to find that out and what it writes for every
/// slave; the share within the radius adds linearly.
#[test]
fn bytes_follow_the_share_within_the_radius() {
    let topo = Topology {
        masters_per_slave: 0.25,
        facets_per_node: 4.0,
        nodes_per_facet: 4.0,
    };
    for pass in [
        &passes::LOCAL_SEARCH,
        &passes::PENALTY_ACTIVE,
        &passes::SCATTER_FORCES_ACTIVE,
    ] {
        let far = bytes_per_slave(pass, &topo, 0.0).unwrap();
        assert_eq!(far, 0.0, "{}", pass.entry);
    }
    let far = bytes_per_slave(&passes::PENALTY, &topo, 0.0).unwrap();
    assert_eq!(far, (WORD + HIT + 2 * STATE + OUT + VEC4) as f64);
    for pass in [&passes::LOCAL_SEARCH, &passes::PENALTY] {
        let far = bytes_per_slave(pass, &topo, 0.0).unwrap();
        let near = bytes_per_slave(pass, &topo, 1.0).unwrap();
        let half = bytes_per_slave(pass, &topo, 0.5).unwrap();
        assert!((half - 0.5 * (far + near)).abs() < 1e-9);
        assert!(near > 4.0 * VEC4 as f64);
    }
    assert_eq!(bytes_per_slave(&passes::TREE_REFIT, &topo, 1.0), None);
}

/// A slave's own records are part of what a pass declares, all of it for a slave beyond
/// the radius in a pair whose slaves are no master nodes; the penalty's own records of a
/// slave in contact are its active index, hit, state in and out, output, velocity and
/// position, the master's its facet and the facet's nodes' positions, velocities and
/// normals.
#[test]
fn a_slaves_own_records_are_those_one_per_slave() {
    let topo = Topology {
        masters_per_slave: 0.25,
        facets_per_node: 4.0,
        nodes_per_facet: 4.0,
    };
    for pass in DECLARED {
        for near in [0.0, 0.3, 1.0] {
            let all = bytes_per_slave(pass, &topo, near).unwrap();
            let own = own_bytes_per_slave(pass, &topo, near).unwrap();
            assert!(own >= 0.0 && own <= all, "{}: {own} of {all}", pass.entry);
        }
    }
    let own = own_bytes_per_slave(&passes::PENALTY_ACTIVE, &topo, 1.0).unwrap();
    assert_eq!(own, (WORD + HIT + 2 * STATE + OUT + 2 * VEC4) as f64);
    let all = bytes_per_slave(&passes::PENALTY_ACTIVE, &topo, 1.0).unwrap();
    assert_eq!(all - own, (VEC4 + 3 * 4 * VEC4) as f64);
    let no_master = Topology {
        masters_per_slave: 0.0,
        ..topo
    };
    for pass in DECLARED {
        assert_eq!(
            own_bytes_per_slave(pass, &no_master, 0.0),
            bytes_per_slave(pass, &no_master, 0.0),
            "{}",
            pass.entry
        );
    }
}

/// A slave beyond the radius, in a pair whose slaves are no master nodes, costs the motion
/// pass its id, position and reference (whose w is its state: 36 bytes) and nothing else in a local
/// increment: the normals and the active gather and add_forces do not visit it (the gather
/// and add_forces over every pair node, which global increments run, read its hit word); a
/// master node under no contact costs the normals, gather and add_forces its need word
/// each.
#[test]
fn a_slave_beyond_the_radius_costs_its_motion_alone() {
    let no_master = Topology {
        masters_per_slave: 0.0,
        facets_per_node: 4.0,
        nodes_per_facet: 4.0,
    };
    let far = |pass| bytes_per_slave(pass, &no_master, 0.0).unwrap();
    assert_eq!(far(&passes::MOTION), (WORD + 2 * VEC4) as f64);
    assert_eq!(far(&passes::NODAL_NORMALS_NEEDED), 0.0);
    assert_eq!(far(&passes::GATHER), WORD as f64);
    assert_eq!(far(&passes::ADD_FORCES), WORD as f64);
    assert_eq!(far(&passes::GATHER_ACTIVE), 0.0);
    assert_eq!(far(&passes::ADD_FORCES_ACTIVE), 0.0);
    let total: f64 = DECLARED
        .iter()
        .filter(|p| p.entry != "integrate")
        .map(|p| far(p))
        .sum();
    assert_eq!(total, 36.0);
    // a master node under no contact: its need word in the normals, gather and add_forces
    let plate = Topology {
        masters_per_slave: 0.25,
        ..no_master
    };
    let far_on_plate = |pass| bytes_per_slave(pass, &plate, 0.0).unwrap();
    let need_word = 0.25 * WORD as f64;
    assert_eq!(far_on_plate(&passes::NODAL_NORMALS_NEEDED), need_word);
    assert_eq!(far_on_plate(&passes::GATHER), WORD as f64 + need_word);
    assert_eq!(far_on_plate(&passes::ADD_FORCES), WORD as f64 + need_word);
    assert_eq!(far_on_plate(&passes::GATHER_ACTIVE), need_word);
    assert_eq!(far_on_plate(&passes::ADD_FORCES_ACTIVE), need_word);
    assert_eq!(far_on_plate(&passes::NEED_NORMALS), 0.0);
}
