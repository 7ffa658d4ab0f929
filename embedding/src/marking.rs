//! Which group element each loop of a user's mesh goes to: the marking, chosen so the map onto the
//! polygon need not stretch short loops into long ones.
//!
//! [`schema::canonicalize`] expresses every greedy loop as a word in the canonical letters, but
//! any automorphism of the surface group gives an equally valid set of words, and they are not
//! equally good: the equivariant map sends loop i (mesh length L_i) to a curve at least as long as
//! the translation length ℓ_i of its element, so where a short loop's word is long (the cut-and-
//! paste wraps it round other handles) the map squeezes the mesh across it and stretches it along
//! it. On the genus-5 cube with tunnels the canonical words ran to 10 letters: the two shortest
//! loops (2.5 and 2.8 long) went to elements 8.3 and 8.6 long, the longest (5.9) to 2.6, and the
//! map came out 782 times longer one way than the other near the base vertex.
//!
//! [`shorten`] walks downhill on Σ ℓ_i² / L_i (the Dirichlet energy of stretching each loop evenly
//! along itself) through [`schema::relator_moves`]: the Dehn twists about each handle's two
//! curves and moves that mix neighbouring handles, each an automorphism that keeps the relator.

use std::collections::HashSet;

use charts::{Geometry, Lft, Polygon};
use mesh::schema::{self, Word};

use crate::mesh_fit::word_element;

/// States kept at each level of the search, levels without a better marking before it stops, and
/// levels at most per handle.
const BEAM: usize = 16;
const PATIENCE: usize = 6;
const LEVELS_PER_HANDLE: usize = 20;

/// The marking's cost and the words that reach it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Marking {
    pub words: Vec<Word>,
    /// Σ ℓ_i² / L_i.
    pub cost: f64,
    /// Moves taken.
    pub steps: usize,
}

/// The translation length of a group element: 2 acosh(|tr| / 2) for the hyperbolic plane's
/// isometries (the matrix scaled to determinant 1), the translation's length in the plane.
pub(crate) fn translation_length(g: &Lft, geometry: Geometry) -> f64 {
    let [a, b, c, d] = g.matrix();
    match geometry {
        // The trace of the matrix scaled to determinant 1 (a product that overflowed, or lost
        // its digits so that it reads as elliptic, is not taken for a short one).
        Geometry::Hyperbolic => {
            let half_trace = (a + d).norm() / (2.0 * (a * d - b * c).sqrt().norm());
            if half_trace.is_finite() && half_trace >= 1.0 - 1e-9 {
                2.0 * half_trace.max(1.0).acosh()
            } else {
                f64::INFINITY
            }
        }
        _ => {
            let t = (b / d).norm();
            if t.is_finite() { t } else { f64::INFINITY }
        }
    }
}

/// The words after a search from `words` (each greedy loop's, in the canonical letters) for the
/// least Σ ℓ_i² / L_i, `lengths` the loops' lengths on the mesh. The result names the same loops'
/// elements under another identification of the surface's group with the polygon's, which the map
/// can use as it is.
///
/// A beam search: each level applies every move to each of the [`BEAM`] best markings of the level
/// before and keeps the best distinct ones, so a marking is reached even where the way there first
/// climbs (a twist that lengthens one loop before the next shortens two). It stops after
/// [`PATIENCE`] levels without a better marking.
pub(crate) fn shorten(words: Vec<Word>, lengths: &[f64], polygon: &Polygon) -> Marking {
    let genus = polygon.genus() as usize;
    let geometry = polygon.geometry();
    let term = |w: &Word, i: usize| {
        let ell = translation_length(&word_element(polygon, w), geometry);
        ell * ell / lengths[i].max(f64::MIN_POSITIVE)
    };
    let terms: Vec<f64> = words.iter().enumerate().map(|(i, w)| term(w, i)).collect();
    let start = State {
        cost: terms.iter().sum(),
        words,
        terms,
        depth: 0,
    };
    // Words longer than this are not explored: an element's numbers lose their digits along a
    // long product, and a long word is a long loop's element anyway.
    let longest = words_cap(&start.words, genus);
    let moves = schema::relator_moves(genus);
    let mut seen: HashSet<u64> = HashSet::from([fingerprint(&start.words)]);
    let mut best = start.clone();
    let mut beam = vec![start];
    let mut stale = 0;
    for _ in 0..LEVELS_PER_HANDLE * genus {
        let mut next: Vec<State> = Vec::new();
        for state in &beam {
            for m in &moves {
                let changed: Vec<(usize, Word)> = state
                    .words
                    .iter()
                    .enumerate()
                    .filter(|(_, w)| m.touches(w))
                    .map(|(i, w)| (i, schema::dehn_reduce(&m.apply(w), genus)))
                    .collect();
                if changed.is_empty() || changed.iter().any(|(_, w)| w.len() > longest) {
                    continue;
                }
                let mut child = state.clone();
                for (i, w) in changed {
                    child.terms[i] = term(&w, i);
                    child.words[i] = w;
                }
                if seen.insert(fingerprint(&child.words)) {
                    child.cost = child.terms.iter().sum();
                    child.depth += 1;
                    next.push(child);
                }
            }
        }
        if next.is_empty() {
            break;
        }
        next.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        next.truncate(BEAM);
        // A relative margin so rounding cannot count as progress.
        if next[0].cost < best.cost * (1.0 - 1e-9) {
            best = next[0].clone();
            stale = 0;
        } else {
            stale += 1;
            if stale >= PATIENCE {
                break;
            }
        }
        beam = next;
    }
    Marking {
        words: best.words,
        cost: best.cost,
        steps: best.depth,
    }
}

/// The longest word the search explores: the longer of the starting words' longest and 2g, half
/// the relator. (On a genus-4 plate, words of 13 letters that the search reached came with
/// products 0.4 from the identity round a triangle in f64: their lengths could not be trusted.)
fn words_cap(words: &[Word], genus: usize) -> usize {
    words.iter().map(Vec::len).max().unwrap_or(0).max(2 * genus)
}

/// A marking's words hashed, to tell markings already reached (a collision only drops a state).
fn fingerprint(words: &[Word]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    words.hash(&mut hasher);
    hasher.finish()
}

/// A marking the search holds: the words, each loop's term of the cost, their sum, and the moves
/// that led to it.
#[derive(Clone)]
struct State {
    words: Vec<Word>,
    terms: Vec<f64>,
    cost: f64,
    depth: usize,
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh::schema::Letter;
    use proptest::prelude::*;

    fn letter(generator: u32) -> Letter {
        Letter {
            generator,
            inverse: false,
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Loops of equal length whose marking was twisted by a few random moves: the descent
        /// brings the cost back to the untwisted marking's (every loop one side pairing), and its
        /// words still satisfy the relation.
        #[test]
        fn the_descent_undoes_a_twisted_marking(
            genus in 2usize..6,
            picks in proptest::collection::vec(0usize..10_000, 1..4),
        ) {
            let polygon = Polygon::new(genus as u32).unwrap();
            let moves = schema::relator_moves(genus);
            let plain: Vec<Word> = (0..2 * genus as u32).map(|g| vec![letter(g)]).collect();
            let mut twisted = plain.clone();
            for p in &picks {
                let m = &moves[p % moves.len()];
                twisted = twisted.iter().map(|w| schema::dehn_reduce(&m.apply(w), genus)).collect();
            }
            let lengths = vec![1.0; 2 * genus];
            let best = shorten(plain, &lengths, &polygon).cost;
            let found = shorten(twisted, &lengths, &polygon);
            prop_assert!(found.cost <= best * (1.0 + 1e-9), "{} against {best}", found.cost);
            let relation = schema::relator(genus);
            let back = schema::substitute(&relation, &found.words);
            prop_assert!(schema::dehn_reduce(&back, genus).is_empty());
        }
    }
}
