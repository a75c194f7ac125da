//! Tests of the evidence grid: votes, majorities, openings.

use super::*;

#[test]
fn without_own_votes_only_holes_are_filled() {
    let mut g =
        EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0), 0.2, 1, 100).unwrap();
    // Transparent votes in columns 1 and 3 of row 2; none in column 2
    // (a hole) or column 4 (beyond the edge).
    for i in [1, 3] {
        g.vote(&g.centre(2 * g.cols + i), 2, 0);
    }
    let edge = 2 * g.cols + 4;
    let hole = 2 * g.cols + 2;
    assert_eq!(g.cell_state(edge), Surface::Transparent);
    assert_eq!(g.cell_state(hole), Surface::Transparent);
    g.fill_between_votes_only = true;
    assert_eq!(g.cell_state(edge), Surface::Unknown);
    assert_eq!(g.cell_state(hole), Surface::Transparent);
}

#[test]
fn glass_hides_only_where_no_bare_pass_or_opaque_majority_is() {
    let mut g =
        EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(2.0, 2.0), 0.2, 1, 100).unwrap();
    let (open, wall, bare) = (
        g.centre(2 * g.cols + 2),
        g.centre(7 * g.cols + 2),
        g.centre(2 * g.cols + 7),
    );
    for _ in 0..3 {
        g.vote_open(&open);
        g.vote(&wall, 0, 1);
        g.vote_bare(&bare);
    }
    g.finalize();
    // Passes far from any echo make a cell Open, yet glass may be there.
    assert_eq!(g.state(&open), Surface::Open);
    assert!(g.could_hide_glass(&open));
    assert!(!g.could_hide_glass(&wall));
    assert!(!g.could_hide_glass(&bare));
    // Outside the grid nothing is known.
    assert!(g.could_hide_glass(&Point2::new(-1.0, -1.0)));
    let k = g.index(&open).unwrap();
    g.set_open(k);
    assert!(!g.could_hide_glass(&open));
}

/// Two panes (rows 0-5 and 8-9, most passes echo) with a 0.4 m gap
/// between them (rows 6-7) passed by as many beams, which never echo. Only
/// the gap's cells at the grid's border touch a non-transparent cell at
/// first; with the deficit test they open, and the rest of the gap opens
/// as its neighbours do. A glass cell inside a pane that echoes as little
/// stays glass (no opening leads to it), and cells predicted fewer than
/// the minimum echoes say nothing.
#[test]
fn cells_that_never_echo_beside_echoing_glass_open_from_the_edge() {
    let grid = |top_passes: u32| {
        let mut g =
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(2.0, 2.0), 0.2, 1, 100).unwrap();
        for k in 0..g.cols * g.rows {
            let (i, j) = (k % g.cols, k / g.cols);
            let c = g.centre(k);
            match (i, j) {
                (_, 6 | 7) => g.vote(&c, top_passes, 0),
                (5, 3) => g.vote(&c, 90, 0),
                _ => {
                    g.vote(&c, 10, 0);
                    for _ in 0..80 {
                        g.vote_echo(&c);
                    }
                }
            }
        }
        g.echo_deficit_min_expected = 30.0;
        g.finalize();
        g
    };
    let (top, second, inside) = (6 * 10 + 4, 7 * 10 + 4, 3 * 10 + 5);
    let mut g = grid(300);
    for k in [top, second, inside] {
        assert_eq!(g.cell_state(k), Surface::Transparent);
    }
    g.echo_deficit_ratio = 0.1;
    g.finalize();
    assert_eq!(g.cell_state(top), Surface::Open, "the gap's lower row");
    assert_eq!(g.cell_state(second), Surface::Open, "its upper row");
    assert_eq!(
        g.cell_state(inside),
        Surface::Transparent,
        "inside the pane"
    );
    assert_eq!(g.cell_state(2 * 10 + 4), Surface::Transparent, "the glass");
    // Passed by few beams (the neighbours' rate predicts about 16 echoes
    // for 20 passes, fewer than 30): kept.
    let mut few = grid(20);
    few.echo_deficit_ratio = 0.1;
    few.finalize();
    assert_eq!(few.cell_state(top), Surface::Transparent);
}

#[test]
fn bare_passes_near_normal_incidence_open_a_transparent_cell() {
    let mut g =
        EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0), 0.2, 1, 100).unwrap();
    let c = g.centre(2 * g.cols + 2);
    g.vote(&c, 5, 0);
    for _ in 0..3 {
        g.vote_bare(&c);
    }
    g.finalize();
    assert_eq!(g.state(&c), Surface::Transparent);
    g.min_bare_passes = 3;
    g.finalize();
    assert_eq!(g.state(&c), Surface::Open);
    // A surface echo in the neighbourhood keeps it glass.
    g.vote_echo(&g.centre(2 * g.cols + 3));
    g.finalize();
    assert_eq!(g.state(&c), Surface::Transparent);
}

#[test]
fn majority_of_the_neighbourhood_decides() {
    let mut g =
        EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0), 0.1, 3, 1000).unwrap();
    assert_eq!(g.state(&Point2::new(0.55, 0.55)), Surface::Unknown);
    g.vote(&Point2::new(0.55, 0.55), 2, 0);
    g.vote(&Point2::new(0.45, 0.55), 0, 1);
    assert_eq!(g.state(&Point2::new(0.55, 0.55)), Surface::Transparent);
    g.vote(&Point2::new(0.65, 0.65), 0, 2);
    assert_eq!(g.state(&Point2::new(0.55, 0.55)), Surface::Opaque);
    assert_eq!(g.state(&Point2::new(5.0, 5.0)), Surface::Unknown);
    assert!(
        EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1e4, 1e4), 0.01, 1, 1000).is_none()
    );
}

/// Beams pass a plane along 4 m, but surface echoes come from its first
/// metre only: with an echo reach of 1 m the far end is open space, not
/// glass; without it, all of it is transparent.
#[test]
fn transparent_cells_far_from_every_echo_are_open() {
    let grid = |reach: f64| {
        let mut g =
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(4.0, 1.0), 0.2, 1, 1000).unwrap();
        g.echo_reach = reach;
        for k in 0..g.cols * g.rows {
            let c = g.centre(k);
            g.vote(&c, 3, 0);
            if c.x < 1.0 {
                g.vote_echo(&c);
            }
        }
        g.finalize();
        g
    };
    let with = grid(1.0);
    assert_eq!(with.state(&Point2::new(0.5, 0.5)), Surface::Transparent);
    assert_eq!(with.state(&Point2::new(1.7, 0.5)), Surface::Transparent);
    assert_eq!(with.state(&Point2::new(3.5, 0.5)), Surface::Open);
    let without = grid(0.0);
    assert_eq!(without.state(&Point2::new(3.5, 0.5)), Surface::Transparent);
}

/// A second landmark on a railing's plane gets almost none of its glass
/// echoes (they go to the first): its transparent region, passed by
/// thousands of beams with a handful of stray echoes, is an opening under
/// a minimum echo fraction; glass whose passes echo a few per cent stays.
#[test]
fn a_transparent_region_almost_without_echoes_is_open() {
    let region = |echoes_per_cell: u32| {
        let mut g =
            EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(2.0, 2.0), 0.2, 1, 100).unwrap();
        for j in 2..6 {
            for i in 2..6 {
                let c = g.centre(j * g.cols + i);
                g.vote(&c, 500, 0);
                for _ in 0..echoes_per_cell {
                    g.vote_echo(&c);
                }
            }
        }
        g
    };
    let c = Point2::new(0.7, 0.7);
    for (echoes, fraction, state) in [
        (0, 0.0, Surface::Transparent),
        (1, 0.005, Surface::Open),
        (25, 0.005, Surface::Transparent),
    ] {
        let mut g = region(echoes);
        g.min_echo_fraction = fraction;
        g.finalize();
        assert_eq!(
            g.state(&c),
            state,
            "{echoes} echoes a cell, fraction {fraction}"
        );
    }
}

/// A single echo away from the near-normal peak is opaque when stronger
/// than the plane's glass echoes at its incidence (range-corrected, so a
/// far wall's faint echo is still a wall), and by the intensity threshold
/// only where no glass echo was met at that incidence; within the peak it
/// never is.
#[test]
fn an_echo_is_opaque_when_stronger_than_the_glass_at_its_incidence() {
    let mut g =
        EvidenceGrid::new(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0), 0.2, 1, 100).unwrap();
    g.peak_cos = 5f64.to_radians().cos();
    g.opaque_intensity = Some(30.0);
    g.range_exponent = 2.0;
    // Glass echoes at 30-40 degrees reach strength 2 (intensity 1 at 10 m).
    g.glass_strength_at[3] = Some(2.0);
    let at = |deg: f64| deg.to_radians().cos();
    // 35 degrees: intensity 1 at 20 m is strength 2.6 (a far wall), 5 at
    // 4 m is 1.9 (glass), though 5 is far below the intensity threshold.
    assert!(g.is_opaque_echo(1.0, 20.0, at(35.0)));
    assert!(!g.is_opaque_echo(5.0, 4.0, at(35.0)));
    assert_eq!(g.stronger_than_glass(5.0, 4.0, at(35.0)), Some(false));
    // 55 degrees: no glass reference, the intensity threshold decides.
    assert_eq!(g.stronger_than_glass(50.0, 4.0, at(55.0)), None);
    assert!(g.is_opaque_echo(50.0, 4.0, at(55.0)));
    assert!(!g.is_opaque_echo(20.0, 40.0, at(55.0)));
    // Within the peak nothing is opaque.
    assert!(!g.is_opaque_echo(1000.0, 4.0, at(2.0)));
}
