//! A system of loops through one base vertex of a closed orientable mesh, and the canonical form of
//! the relation it satisfies.
//!
//! [`loop_system`] grows Erickson and Whittlesey's greedy homotopy basis: a shortest-path tree T from
//! the base vertex, a dual spanning tree C of the remaining edges that keeps the longest loops (so the
//! 2g edges left over, the *generators*, close the shortest loops), and the word that the disk cut
//! along T and the generators reads round its boundary. That word is one relation among 2g letters,
//! each appearing once forwards and once backwards, but in no particular order.
//!
//! [`canonicalize`] brings it to the canonical form a₁ b₁ a₁⁻¹ b₁⁻¹ … a_g b_g a_g⁻¹ b_g⁻¹ by the cut-and-
//! paste of the classification of surfaces, done on words: each step is a change of generators
//! (an automorphism of the free group), and the result says what each original generator is as a
//! word in the canonical ones. A map of the surface onto the fundamental polygon needs no more: send
//! the canonical letters to the polygon's side pairings, and each generator edge to its word.
//!
//! ```
//! use mesh::schema::{Letter, canonicalize, cyclically_equal, substitute};
//!
//! // The octagon with opposite sides glued, a b c d a⁻¹ b⁻¹ c⁻¹ d⁻¹, is a genus-2 surface too.
//! let w = |s: &[i32]| s.iter().map(|&i| Letter::from_signed(i)).collect::<Vec<_>>();
//! let relation = w(&[1, 2, 3, 4, -1, -2, -3, -4]);
//! let canonical = canonicalize(&relation, 4)?;
//! let back = substitute(&relation, &canonical.originals);
//! assert!(cyclically_equal(&back, &w(&[1, 2, -1, -2, 3, 4, -3, -4])));
//! # Ok::<(), mesh::schema::SchemaError>(())
//! ```

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::HalfEdgeMesh;
use crate::halfedge::UnionFind;

/// A generator or its inverse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Letter {
    pub generator: u32,
    pub inverse: bool,
}

/// A word in the generators, read left to right.
pub type Word = Vec<Letter>;

impl Letter {
    /// ±(i + 1) ↦ generator i, inverse when negative (0 is not a letter).
    pub fn from_signed(s: i32) -> Letter {
        assert!(s != 0, "0 is not a letter");
        Letter {
            generator: s.unsigned_abs() - 1,
            inverse: s < 0,
        }
    }

    pub fn inv(self) -> Letter {
        Letter {
            inverse: !self.inverse,
            ..self
        }
    }
}

/// What can go wrong in finding or reducing a loop system.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SchemaError {
    #[error("the mesh is not closed, manifold and oriented: {0}")]
    NotClosed(String),
    #[error("the mesh is not connected: vertex {0} cannot be reached from the base vertex")]
    Disconnected(u32),
    #[error("the loop system is inconsistent: {0}")]
    Inconsistent(String),
}

/// The role of an edge in the tree–cotree decomposition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeRole {
    /// On the shortest-path tree from the base vertex.
    Tree,
    /// Crossed by the dual spanning tree: inside the cut disk.
    Cotree,
    /// Generator i: its loop is tree path, this edge, tree path back. `forward` when this half-edge
    /// runs the way generator i's loop does.
    Generator { index: u32, forward: bool },
}

/// A greedy system of loops through `base`, and the relation its loops satisfy.
#[derive(Clone, Debug)]
pub struct LoopSystem {
    pub base: u32,
    /// Per half-edge.
    pub roles: Vec<EdgeRole>,
    /// Per generator: the half-edge its loop runs along.
    pub generators: Vec<u32>,
    /// Per vertex: the tree half-edge arriving from its parent (None at the base).
    pub parent: Vec<Option<u32>>,
    /// Distance from the base along the tree.
    pub distance: Vec<f64>,
    /// The boundary word of the disk cut along the tree and the generators, counter-clockwise.
    pub relation: Word,
    /// Cotree half-edges in an order in which each is the last unknown edge of its face: a holonomy
    /// known on the tree and the generators extends to every edge by solving these in turn.
    pub peel: Vec<u32>,
    /// The face left after peeling: its three half-edges are all known before it is reached, so it
    /// checks the relation.
    pub root_face: u32,
}

impl LoopSystem {
    /// The loop of generator i as a closed vertex path from the base (first and last entry: base).
    pub fn loop_path(&self, mesh: &HalfEdgeMesh, i: usize) -> Vec<u32> {
        let h = self.generators[i];
        let mut path = self.tree_path(mesh, mesh.origin(h));
        let mut back = self.tree_path(mesh, mesh.target(h));
        back.reverse();
        path.extend(back);
        path
    }

    /// The tree path from the base to v.
    fn tree_path(&self, mesh: &HalfEdgeMesh, mut v: u32) -> Vec<u32> {
        let mut path = vec![v];
        while let Some(h) = self.parent[v as usize] {
            v = mesh.origin(h);
            path.push(v);
        }
        path.reverse();
        path
    }
}

/// The greedy system of loops through `base` (see the module). `length(h)` is half-edge h's length,
/// the same both ways. The mesh must be closed, manifold, oriented and connected.
pub fn loop_system(
    mesh: &HalfEdgeMesh,
    length: impl Fn(u32) -> f64,
    base: u32,
) -> Result<LoopSystem, SchemaError> {
    let h_count = mesh.halfedge_count();
    let twin = |h: u32| {
        mesh.twin(h)
            .ok_or_else(|| SchemaError::NotClosed(format!("half-edge {h} has no twin")))
    };
    for h in 0..h_count as u32 {
        twin(h)?;
    }
    let (parent, distance) = shortest_path_tree(mesh, &length, base)?;
    let mut roles = vec![EdgeRole::Cotree; h_count];
    for h in parent.iter().flatten() {
        roles[*h as usize] = EdgeRole::Tree;
        roles[twin(*h)? as usize] = EdgeRole::Tree;
    }
    // The dual tree keeps the longest loops: Kruskal over non-tree edges, longest first.
    let mut candidates: Vec<(f64, u32)> = (0..h_count as u32)
        .filter(|&h| roles[h as usize] != EdgeRole::Tree && h < mesh.twin(h).unwrap_or(0))
        .map(|h| {
            let d =
                distance[mesh.origin(h) as usize] + length(h) + distance[mesh.target(h) as usize];
            (d, h)
        })
        .collect();
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut faces = UnionFind::new(mesh.face_count());
    let mut generators = Vec::new();
    for (_, h) in candidates {
        let t = twin(h)?;
        if !faces.union(mesh.face(h), mesh.face(t)) {
            let index = generators.len() as u32;
            roles[h as usize] = EdgeRole::Generator {
                index,
                forward: true,
            };
            roles[t as usize] = EdgeRole::Generator {
                index,
                forward: false,
            };
            generators.push(h);
        }
    }
    let relation = boundary_word(mesh, &roles, &generators)?;
    let (peel, root_face) = peel_order(mesh, &roles)?;
    Ok(LoopSystem {
        base,
        roles,
        generators,
        parent,
        distance,
        relation,
        peel,
        root_face,
    })
}

type Tree = (Vec<Option<u32>>, Vec<f64>);

/// Dijkstra from `base`: per vertex the half-edge from its parent, and its distance.
fn shortest_path_tree(
    mesh: &HalfEdgeMesh,
    length: &impl Fn(u32) -> f64,
    base: u32,
) -> Result<Tree, SchemaError> {
    let n = mesh.vertex_count();
    let outgoing = mesh.outgoing();
    let mut distance = vec![f64::INFINITY; n];
    let mut parent = vec![None; n];
    let mut done = vec![false; n];
    let mut heap = BinaryHeap::new();
    distance[base as usize] = 0.0;
    heap.push(Reverse((Ordered(0.0), base)));
    while let Some(Reverse((Ordered(d), v))) = heap.pop() {
        if std::mem::replace(&mut done[v as usize], true) {
            continue;
        }
        for &h in &outgoing[v as usize] {
            let u = mesh.target(h) as usize;
            let du = d + length(h);
            if du < distance[u] {
                distance[u] = du;
                parent[u] = Some(h);
                heap.push(Reverse((Ordered(du), u as u32)));
            }
        }
    }
    if let Some(v) = done.iter().position(|d| !d) {
        return Err(SchemaError::Disconnected(v as u32));
    }
    Ok((parent, distance))
}

/// The counter-clockwise boundary of the disk that the cotree edges hold together, as the word of
/// the generator half-edges met (tree edges read as nothing).
fn boundary_word(
    mesh: &HalfEdgeMesh,
    roles: &[EdgeRole],
    generators: &[u32],
) -> Result<Word, SchemaError> {
    let Some(&start) = generators.first() else {
        return Ok(Vec::new());
    };
    let expected = 2 * (mesh.vertex_count() - 1 + generators.len());
    let mut word = Vec::new();
    let (mut h, mut steps) = (start, 0);
    loop {
        if let EdgeRole::Generator { index, forward } = roles[h as usize] {
            word.push(Letter {
                generator: index,
                inverse: !forward,
            });
        }
        steps += 1;
        if steps > expected {
            break;
        }
        // Turn round the target vertex across interior (cotree) edges to the next boundary edge.
        let mut next = mesh.next(h);
        while roles[next as usize] == EdgeRole::Cotree {
            next = mesh.next(mesh.twin(next).expect("closed: checked"));
        }
        h = next;
        if h == start {
            break;
        }
    }
    if steps != expected {
        return Err(SchemaError::Inconsistent(format!(
            "the cut disk's boundary has {steps} edges, expected {expected}"
        )));
    }
    Ok(word)
}

/// Cotree half-edges in peeling order (leaves of the dual tree first), and the root face.
fn peel_order(mesh: &HalfEdgeMesh, roles: &[EdgeRole]) -> Result<(Vec<u32>, u32), SchemaError> {
    let f_count = mesh.face_count();
    let unknown_in = |f: u32| {
        mesh.face_halfedges(f)
            .filter(|&h| roles[h as usize] == EdgeRole::Cotree)
            .count()
    };
    let mut unknown: Vec<usize> = (0..f_count as u32).map(unknown_in).collect();
    let mut solved = vec![false; mesh.halfedge_count()];
    let mut queue: Vec<u32> = (0..f_count as u32)
        .filter(|&f| unknown[f as usize] == 1)
        .collect();
    let mut peel = Vec::with_capacity(f_count);
    let mut done = vec![false; f_count];
    while let Some(f) = queue.pop() {
        if done[f as usize] || unknown[f as usize] != 1 {
            continue;
        }
        let h = mesh
            .face_halfedges(f)
            .find(|&h| roles[h as usize] == EdgeRole::Cotree && !solved[h as usize])
            .expect("one unknown edge");
        let t = mesh.twin(h).expect("closed: checked");
        solved[h as usize] = true;
        solved[t as usize] = true;
        done[f as usize] = true;
        unknown[f as usize] = 0;
        peel.push(h);
        let g = mesh.face(t) as usize;
        unknown[g] -= 1;
        if unknown[g] == 1 {
            queue.push(g as u32);
        }
    }
    let left: Vec<usize> = (0..f_count).filter(|&f| !done[f]).collect();
    match left[..] {
        [root] if unknown[root] == 0 => Ok((peel, root as u32)),
        _ => Err(SchemaError::Inconsistent(format!(
            "{} faces are left after peeling the dual tree",
            left.len()
        ))),
    }
}

/// An f64 ordered by `total_cmp`, for the heap.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ordered(f64);
impl Eq for Ordered {}
impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

// ------------------------------------------------------------------------------------ words

/// The result of [`canonicalize`]: the canonical letters are 2k = a_k and 2k + 1 = b_k.
#[derive(Clone, Debug)]
pub struct Canonical {
    /// Each original generator as a word in the canonical letters.
    pub originals: Vec<Word>,
}

/// The inverse of a word.
pub fn inverse(w: &[Letter]) -> Word {
    w.iter().rev().map(|l| l.inv()).collect()
}

/// Cancels adjacent x x⁻¹ pairs.
pub fn free_reduce(w: &[Letter]) -> Word {
    let mut out: Word = Vec::with_capacity(w.len());
    for &l in w {
        if out.last() == Some(&l.inv()) {
            out.pop();
        } else {
            out.push(l);
        }
    }
    out
}

/// Free reduction, then cancellation between the two ends (as a cyclic word).
pub fn cyclic_reduce(w: &[Letter]) -> Word {
    let mut w = free_reduce(w);
    while w.len() >= 2 && w[0] == w[w.len() - 1].inv() {
        w.pop();
        w.remove(0);
    }
    w
}

/// Whether two words are equal as cyclic words (after cyclic reduction).
pub fn cyclically_equal(a: &[Letter], b: &[Letter]) -> bool {
    let (a, b) = (cyclic_reduce(a), cyclic_reduce(b));
    a.len() == b.len()
        && (a.is_empty()
            || (0..a.len()).any(|s| (0..a.len()).all(|i| a[(i + s) % a.len()] == b[i])))
}

/// `word` with each generator i replaced by `images[i]`, freely reduced.
pub fn substitute(word: &[Letter], images: &[Word]) -> Word {
    let mut out = Vec::new();
    for l in word {
        let image = &images[l.generator as usize];
        if l.inverse {
            out.extend(inverse(image));
        } else {
            out.extend_from_slice(image);
        }
    }
    free_reduce(&out)
}

/// The canonical form of `relation`, a cyclic word in `generators` letters each appearing once
/// forwards and once backwards, whose corners are all one vertex (as the boundary word of a disk cut
/// along loops through one base vertex is). See the module.
///
/// Each step takes two linked letters, a … b … a⁻¹ … b⁻¹ read from some rotation, as
/// a P b Q a⁻¹ R b⁻¹ S, and changes generators: b = P⁻¹ c Q⁻¹, then a = R Q f, which turns the word
/// into f c f⁻¹ c⁻¹ P S R Q. Of all such pairs and rotations it takes the one with the shortest
/// P Q R, since their letters are what the originals' words grow by. Letters of finished handles
/// are never chosen again, and a handle f c f⁻¹ c⁻¹ lies whole inside P, Q, R or S, so it stays whole.
pub fn canonicalize(relation: &[Letter], generators: usize) -> Result<Canonical, SchemaError> {
    let bad = |why: &str| SchemaError::Inconsistent(why.to_string());
    let mut word = free_reduce(relation);
    let mut uses = vec![[0usize; 2]; generators];
    for l in &word {
        match uses.get_mut(l.generator as usize) {
            Some(u) => u[usize::from(l.inverse)] += 1,
            None => return Err(bad("a letter is not a generator")),
        }
    }
    if !generators.is_multiple_of(2) || uses.iter().any(|u| *u != [1, 1]) {
        return Err(bad(
            "the relation does not use every generator once each way",
        ));
    }
    // originals[i]: original generator i in the current letters (which reuse the indices).
    let mut originals: Vec<Word> = (0..generators as u32).map(|g| vec![letter(g)]).collect();
    let mut finished = vec![false; generators];
    for _ in 0..generators / 2 {
        let step = tightest_pair(&word, &finished)
            .ok_or_else(|| bad("a letter is linked with no other"))?;
        word.rotate_left(step.rotation);
        let (a, b) = (step.a, step.b);
        if word[0].inverse {
            flip(&mut word, &mut originals, a);
        }
        let a_back = position(&word, a, true);
        let b_first = word
            .iter()
            .position(|l| l.generator == b)
            .expect("b occurs");
        if word[b_first].inverse {
            flip(&mut word, &mut originals, b);
        }
        let b_back = position(&word, b, true);
        let p = word[1..b_first].to_vec();
        let q = word[b_first + 1..a_back].to_vec();
        let r = word[a_back + 1..b_back].to_vec();
        let s = word[b_back + 1..].to_vec();
        // b = P⁻¹ c Q⁻¹ (c takes b's index): the word becomes a c a⁻¹ R Q c⁻¹ P S.
        let b_image = free_reduce(&[inverse(&p), vec![letter(b)], inverse(&q)].concat());
        replace(&mut originals, b, &b_image);
        // a = R Q f (f takes a's index): it becomes f c f⁻¹ c⁻¹ P S R Q.
        let a_image = free_reduce(&[r.clone(), q.clone(), vec![letter(a)]].concat());
        replace(&mut originals, a, &a_image);
        let (f, c) = (letter(a), letter(b));
        word = [vec![f, c, f.inv(), c.inv()], p, s, r, q].concat();
        finished[a as usize] = true;
        finished[b as usize] = true;
    }
    // The word is now a product of handles f c f⁻¹ c⁻¹ starting at 0: name them in order.
    let mut rename = vec![u32::MAX; generators];
    for (k, handle) in word.chunks(4).enumerate() {
        let (f, c) = (handle[0], handle[1]);
        if f.inverse || c.inverse || handle[2] != f.inv() || handle[3] != c.inv() {
            return Err(bad("the reduced word is not a product of commutators"));
        }
        rename[f.generator as usize] = 2 * k as u32;
        rename[c.generator as usize] = 2 * k as u32 + 1;
    }
    let originals = originals
        .into_iter()
        .map(|w| {
            w.into_iter()
                .map(|l| Letter {
                    generator: rename[l.generator as usize],
                    ..l
                })
                .collect()
        })
        .collect();
    Ok(Canonical { originals })
}

/// One step of [`canonicalize`]: rotate the word left by `rotation`, then a leads and b is linked
/// with it.
struct Step {
    rotation: usize,
    a: u32,
    b: u32,
}

/// The unfinished linked pair and rotation a P b Q a⁻¹ R b⁻¹ S with the shortest P Q R.
fn tightest_pair(word: &[Letter], finished: &[bool]) -> Option<Step> {
    let n = word.len();
    let mut at = vec![[usize::MAX; 2]; finished.len()];
    for (i, l) in word.iter().enumerate() {
        let slot = &mut at[l.generator as usize];
        let k = usize::from(slot[0] != usize::MAX);
        slot[k] = i;
    }
    let mut best: Option<(usize, Step)> = None;
    for (a, occurrences) in at.iter().enumerate() {
        if finished[a] {
            continue;
        }
        for (i, j) in [
            (occurrences[0], occurrences[1]),
            (occurrences[1], occurrences[0]),
        ] {
            let rot = |x: usize| (x + n - i) % n;
            let j = rot(j);
            for (b, other) in at.iter().enumerate() {
                if b == a || finished[b] {
                    continue;
                }
                let (k, l) = (rot(other[0]), rot(other[1]));
                let (inside, outside) = if k < j { (k, l) } else { (l, k) };
                if inside < j && outside > j && best.as_ref().is_none_or(|(c, _)| outside < *c) {
                    let step = Step {
                        rotation: i,
                        a: a as u32,
                        b: b as u32,
                    };
                    best = Some((outside, step));
                }
            }
        }
    }
    best.map(|(_, step)| step)
}

fn letter(generator: u32) -> Letter {
    Letter {
        generator,
        inverse: false,
    }
}

fn position(word: &[Letter], generator: u32, inverse: bool) -> usize {
    word.iter()
        .position(|l| l.generator == generator && l.inverse == inverse)
        .expect("every letter occurs both ways")
}

/// Renames generator g to its inverse: flips its letters in the word and in the originals.
fn flip(word: &mut [Letter], originals: &mut [Word], g: u32) {
    let flip_in = |w: &mut [Letter]| {
        w.iter_mut()
            .filter(|l| l.generator == g)
            .for_each(|l| l.inverse = !l.inverse)
    };
    flip_in(word);
    originals.iter_mut().for_each(|w| flip_in(w));
}

/// Replaces generator g by `image` in every original's expression.
fn replace(originals: &mut [Word], g: u32, image: &[Letter]) {
    let inv = inverse(image);
    for w in originals.iter_mut() {
        let mut out = Vec::with_capacity(w.len());
        for l in w.iter() {
            match (l.generator == g, l.inverse) {
                (false, _) => out.push(*l),
                (true, false) => out.extend_from_slice(image),
                (true, true) => out.extend_from_slice(&inv),
            }
        }
        *w = free_reduce(&out);
    }
}

/// The canonical relator ∏ₖ a_k b_k a_k⁻¹ b_k⁻¹ (k = 0 … g − 1, a_k = letter 2k, b_k = 2k + 1).
pub fn relator(genus: usize) -> Word {
    (0..genus as u32)
        .flat_map(|k| {
            let (a, b) = (letter(2 * k), letter(2 * k + 1));
            [a, b, a.inv(), b.inv()]
        })
        .collect()
}

/// A change of the canonical letters that takes the relator to itself or to a conjugate of
/// itself, and that another such change undoes, so it is an automorphism of the surface group (a
/// mapping class, as a Dehn twist acts on the loops): the letters it changes and their images;
/// every other letter stays.
#[derive(Clone, Debug, PartialEq)]
pub struct Move {
    pub images: Vec<(u32, Word)>,
}

impl Move {
    /// `word` with the move's images put in, freely reduced.
    pub fn apply(&self, word: &[Letter]) -> Word {
        let mut out = Vec::with_capacity(word.len() + 4);
        for &l in word {
            match self.images.iter().find(|(g, _)| *g == l.generator) {
                Some((_, image)) if l.inverse => out.extend(inverse(image)),
                Some((_, image)) => out.extend_from_slice(image),
                None => out.push(l),
            }
        }
        free_reduce(&out)
    }

    /// Whether the move changes any of these generators' letters.
    pub fn touches(&self, word: &[Letter]) -> bool {
        word.iter()
            .any(|l| self.images.iter().any(|(g, _)| *g == l.generator))
    }
}

/// Pair moves on handles k and k + 1, written with 1 = a_k, 2 = b_k, 3 = a_{k+1}, 4 = b_{k+1}
/// (negative: inverse), the images of the four letters in that order. Found by a search over
/// compositions of up to four elementary Nielsen moves x ↦ x y^{±1}, y^{±1} x on the genus-2
/// relator that bring it to a conjugate u R u⁻¹, then conjugated back by u so that the product of
/// the two commutators is kept exactly (and with it the relator of any genus). The first two undo
/// each other, and so do the last two (the tests check that each move's inverse is in the list).
const PAIR_MOVES: [[&[i8]; 4]; 4] = [
    [&[1, -3, 2], &[-2, 3, 2, -3, 2], &[-2, 3, 2], &[4, -3, 2]],
    [&[1, -2, 3], &[-3, 2, 3], &[-3, 2, 3, -2, 3], &[4, -2, 3]],
    [
        &[1, 4, 2],
        &[-2, -4, 2, 4, 2],
        &[-2, -4, 2, 4, 3, 4, 2],
        &[-2, 4, 2],
    ],
    [
        &[1, -2, -4],
        &[4, 2, -4],
        &[4, 2, -4, -2, 3, -2, -4],
        &[4, 2, 4, -2, -4],
    ],
];

/// Moves a search can change the marking by, step by step: per handle the four transvections
/// b ↦ b a^{±1} and a ↦ a b^{±1} (the Dehn twists about a_k and b_k, which keep
/// a_k b_k a_k⁻¹ b_k⁻¹); and per pair of neighbouring handles four moves found by a search (which
/// mix them, as the twists about curves running through both handles do). Each has its inverse in
/// the list. (The twists about curves round runs of handles, x ↦ Q x Q⁻¹, were tried too: their
/// images are 9 letters or more, which the search's cap on word length leaves out, and on issue
/// 14's meshes they changed nothing.)
pub fn relator_moves(genus: usize) -> Vec<Move> {
    let g = genus as u32;
    let mut moves = Vec::new();
    for k in 0..g {
        let (a, b) = (letter(2 * k), letter(2 * k + 1));
        for s in [a, a.inv()] {
            moves.push(Move {
                images: vec![(b.generator, vec![b, s])],
            });
        }
        for s in [b, b.inv()] {
            moves.push(Move {
                images: vec![(a.generator, vec![a, s])],
            });
        }
    }
    // Handles are neighbours round the relator's cycle too (g − 1 and 0): a move that keeps
    // [h_{g−1}][h_0] keeps the relator's rotation that starts with them, so it takes the relator
    // to a conjugate of itself, which is as good (the group is the same).
    let pairs = if g >= 2 { g } else { 0 };
    for k in 0..pairs {
        let named = |i: i8| {
            let handle = (k + u32::from(i.unsigned_abs() > 2)) % g;
            let l = letter(2 * handle + u32::from(i.unsigned_abs().is_multiple_of(2)));
            if i < 0 { l.inv() } else { l }
        };
        for images in PAIR_MOVES {
            moves.push(Move {
                images: (1..=4i8)
                    .map(|i| {
                        let image = images[i as usize - 1].iter().map(|&x| named(x)).collect();
                        (named(i).generator, image)
                    })
                    .collect(),
            });
        }
    }
    moves
}

/// Dehn's algorithm for the surface group ⟨a₁, b₁, … | ∏[a_k, b_k]⟩ (genus ≥ 2): while the word
/// holds more than half of a cyclic rotation of the relator or its inverse, replace that part by the
/// inverse of the rest. The result is shorter, equal in the group, and (by small cancellation
/// theory: pieces have length 1, under a sixth of the relator's 4g) empty exactly when the word is
/// the identity. Genus 1's group is Z², where the word becomes a^m b^n.
pub fn dehn_reduce(word: &[Letter], genus: usize) -> Word {
    let mut w = free_reduce(word);
    if genus == 1 {
        // Z²: a^m b^n.
        let power = |g: u32| {
            w.iter()
                .filter(|l| l.generator == g)
                .map(|l| if l.inverse { -1i64 } else { 1 })
                .sum::<i64>()
        };
        let repeat = |g: u32, n: i64| {
            let l = Letter {
                generator: g,
                inverse: n < 0,
            };
            std::iter::repeat_n(l, n.unsigned_abs() as usize)
        };
        return repeat(0, power(0)).chain(repeat(1, power(1))).collect();
    }
    if genus < 2 {
        return w;
    }
    let relator = relator(genus);
    let len = relator.len();
    // The relator and its inverse, read cyclically. Each letter occurs once in either, so a part
    // starting at w[start] can only start where that letter does.
    let cycles = [relator.clone(), inverse(&relator)];
    // Where a letter stands in the relator (a_k b_k a_k⁻¹ b_k⁻¹ from 4k) and in its inverse
    // (where x stands at len − 1 minus x⁻¹'s place in the relator); None past the relator's letters.
    let in_relator = |l: Letter| {
        let (k, t) = (l.generator as usize / 2, l.generator as usize % 2);
        (k < genus).then_some(4 * k + t + 2 * usize::from(l.inverse))
    };
    let starts = |l: Letter| Some([in_relator(l)?, len - 1 - in_relator(l.inv())?]);
    'outer: loop {
        // Only a word longer than half the relator can hold more than half of it.
        if 2 * w.len() <= len {
            return w;
        }
        for start in 0..w.len() {
            // A letter that is not the relator's matches nothing.
            let Some(at) = starts(w[start]) else {
                continue;
            };
            for (r, s) in cycles.iter().zip(at) {
                let matched = (0..len.min(w.len() - start))
                    .take_while(|&k| w[start + k] == r[(s + k) % len])
                    .count();
                if 2 * matched > len {
                    let rest: Word = (matched..len).map(|k| r[(s + k) % len]).collect();
                    let mut next = w[..start].to_vec();
                    next.extend(inverse(&rest));
                    next.extend_from_slice(&w[start + matched..]);
                    w = free_reduce(&next);
                    continue 'outer;
                }
            }
        }
        return w;
    }
}

/// Per half-edge u → v: the word of the group element that carries v's lift into u's frame, in the
/// canonical letters, with `words[i]` on generator i's edge, the empty word on tree edges, and the
/// cotree edges solved so that every triangle's three words multiply to the identity. Worked out on
/// words (each reduced by [`dehn_reduce`]), not on matrices: a chain of products along the dual tree
/// loses every digit at genus 8, while the words of short loops stay short. The last triangle's
/// product must reduce to the empty word, which checks the relation exactly.
pub fn edge_words(
    mesh: &HalfEdgeMesh,
    system: &LoopSystem,
    words: &[Word],
    genus: usize,
) -> Result<Vec<Word>, SchemaError> {
    let mut out = vec![Vec::new(); mesh.halfedge_count()];
    for (h, role) in system.roles.iter().enumerate() {
        if let EdgeRole::Generator { index, forward } = *role {
            let w = &words[index as usize];
            out[h] = if forward { w.clone() } else { inverse(w) };
        }
    }
    for &h in &system.peel {
        let (n1, n2) = (mesh.next(h), mesh.next(mesh.next(h)));
        let solved = dehn_reduce(
            &inverse(&[&out[n1 as usize][..], &out[n2 as usize][..]].concat()),
            genus,
        );
        let t = mesh.twin(h).expect("closed: checked by loop_system");
        out[t as usize] = inverse(&solved);
        out[h as usize] = solved;
    }
    let around: Word = mesh
        .face_halfedges(system.root_face)
        .flat_map(|h| out[h as usize].clone())
        .collect();
    if !dehn_reduce(&around, genus).is_empty() {
        return Err(SchemaError::Inconsistent(
            "the words round the last triangle do not multiply to the identity".into(),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every move keeps the relator letter for letter at every genus it applies to (the pair moves
    /// on handles g − 1 and 0 up to conjugation: they keep its rotation that starts with handle
    /// g − 1), changes some letter, and is undone by another move of the list.
    #[test]
    fn relator_moves_keep_the_relator_and_come_with_their_inverses() {
        for genus in 1..=6 {
            let relator = relator(genus);
            let moves = relator_moves(genus);
            let pairs = if genus >= 2 { genus } else { 0 };
            assert_eq!(moves.len(), 4 * genus + PAIR_MOVES.len() * pairs);
            let wrapping = 4 * genus + PAIR_MOVES.len() * pairs.saturating_sub(1);
            for (i, m) in moves.iter().enumerate() {
                let moved = m.apply(&relator);
                if i < wrapping {
                    assert_eq!(moved, relator, "genus {genus}: {m:?}");
                } else {
                    assert!(cyclically_equal(&moved, &relator), "genus {genus}: {m:?}");
                }
                assert!(m.images.iter().any(|(g, w)| w != &vec![letter(*g)]));
                let undone = moves.iter().any(|back| {
                    (0..2 * genus as u32).all(|g| back.apply(&m.apply(&[letter(g)])) == [letter(g)])
                });
                assert!(undone, "genus {genus}: no move undoes {m:?}");
            }
        }
    }

    /// The first move, the twist b₀ ↦ b₀ a₀, changes only words with b₀ in them, and substitutes.
    #[test]
    fn a_move_substitutes_its_letters_and_touches_nothing_else() {
        let twist = &relator_moves(3)[0];
        let (a0, b0, a1, b2) = (letter(0), letter(1), letter(2), letter(5));
        assert!(twist.touches(&[a1, b0.inv()]));
        assert!(!twist.touches(&[a0, a1, b2.inv()]));
        assert_eq!(twist.apply(&[a0, a1, b2.inv()]), vec![a0, a1, b2.inv()]);
        // a₀ b₀ a₀⁻¹ ↦ a₀ b₀ a₀ a₀⁻¹ = a₀ b₀, and b₀⁻¹ ↦ a₀⁻¹ b₀⁻¹.
        assert_eq!(twist.apply(&[a0, b0, a0.inv()]), vec![a0, b0]);
        assert_eq!(twist.apply(&[b0.inv()]), vec![a0.inv(), b0.inv()]);
    }

    /// Dehn's algorithm written plainly (every rotation of the relator and its inverse at every
    /// start, as it was before the letters' places were looked up), as the oracle.
    fn plain_dehn_reduce(word: &[Letter], genus: usize) -> Word {
        let mut w = free_reduce(word);
        let relator = relator(genus);
        let len = relator.len();
        let rotations: Vec<Word> = [relator.clone(), inverse(&relator)]
            .iter()
            .flat_map(|r| {
                (0..len).map(move |s| {
                    let mut r = r.clone();
                    r.rotate_left(s);
                    r
                })
            })
            .collect();
        'outer: loop {
            for start in 0..w.len() {
                for r in &rotations {
                    let matched = w[start..].iter().zip(r).take_while(|(x, y)| x == y).count();
                    if 2 * matched > len {
                        let mut next = w[..start].to_vec();
                        next.extend(inverse(&r[matched..]));
                        next.extend_from_slice(&w[start + matched..]);
                        w = free_reduce(&next);
                        continue 'outer;
                    }
                }
            }
            return w;
        }
    }

    proptest::proptest! {
        /// Dehn's algorithm gives the oracle's word on random words (with letters beyond the
        /// relator's too, which match nothing), and on words that hold most of the relator.
        #[test]
        fn dehn_reduce_agrees_with_the_plain_algorithm(
            genus in 2usize..6,
            letters in proptest::collection::vec((0u32..12, proptest::bool::ANY), 0..30),
            cut in 0usize..24,
            keep in 0usize..24,
        ) {
            let mut word: Word = letters
                .iter()
                .map(|&(g, inverse)| Letter { generator: g % (2 * genus as u32 + 2), inverse })
                .collect();
            // Most of a rotation of the relator spliced in, so the reductions are exercised.
            let r = relator(genus);
            let len = r.len();
            let part: Word = (0..len / 2 + 1 + keep % (len / 2)).map(|k| r[(cut + k) % len]).collect();
            let at = cut.min(word.len());
            word.splice(at..at, part);
            proptest::prop_assert_eq!(dehn_reduce(&word, genus), plain_dehn_reduce(&word, genus));
        }
    }
}
