//! A straight-line expression DAG over `+ − × neg`, built with hash-consing so
//! that equal subexpressions are one node (common-subexpression sharing), and
//! folded as it is built so that structural zeros and ones never reach the
//! emitted code.
//!
//! Folding rules are exact for finite values (`x·0 = 0`, `x − x = 0`), which is
//! what a kinematic chain computes; they are not IEEE-exact for NaN or ∞.

use std::collections::HashMap;

/// A node handle; ids increase in creation order, so id order is a valid
/// evaluation (topological) order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Id(u32);

impl Id {
    /// The node's position in the graph.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A leaf: what the generated function receives. Joint trig (or a prismatic
/// joint's reading) comes once per pose, parameter trig once per parameter
/// set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Input {
    /// cos of revolute joint `j`'s reading `q_j`.
    CosQ(usize),
    /// sin of revolute joint `j`'s reading `q_j`.
    SinQ(usize),
    /// Prismatic joint `j`'s reading `q_j` itself (mm).
    Q(usize),
    /// cos of zero offset `θ_j`.
    CosTheta(usize),
    /// sin of zero offset `θ_j`.
    SinTheta(usize),
    /// cos of twist `α_j`.
    CosAlpha(usize),
    /// sin of twist `α_j`.
    SinAlpha(usize),
    /// Link length `a_j`.
    A(usize),
    /// Link offset `d_j`.
    D(usize),
    /// cos of the Hayati rotation `β_j` (extended chain only).
    CosBeta(usize),
    /// sin of the Hayati rotation `β_j` (extended chain only).
    SinBeta(usize),
    /// Probe offset component (0 = x, 1 = y, 2 = z).
    Probe(usize),
}

/// One operation of the DAG.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    /// A leaf.
    Input(Input),
    /// A constant, stored as its bit pattern so that nodes hash.
    Const(u64),
    /// Sum (operands in canonical order).
    Add(Id, Id),
    /// Difference.
    Sub(Id, Id),
    /// Product (operands in canonical order).
    Mul(Id, Id),
    /// Negation.
    Neg(Id),
}

/// The expression DAG.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    nodes: Vec<Node>,
    index: HashMap<Node, Id>,
}

impl Graph {
    /// An empty graph.
    pub fn new() -> Graph {
        Graph::default()
    }

    /// All nodes in evaluation order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The node behind a handle.
    pub fn node(&self, id: Id) -> Node {
        self.nodes[id.index()]
    }

    fn intern(&mut self, node: Node) -> Id {
        if let Some(&id) = self.index.get(&node) {
            return id;
        }
        let id = Id(u32::try_from(self.nodes.len()).expect("graph under 2^32 nodes"));
        self.nodes.push(node);
        self.index.insert(node, id);
        id
    }

    /// A leaf.
    pub fn input(&mut self, input: Input) -> Id {
        self.intern(Node::Input(input))
    }

    /// A constant (−0 is stored as +0 so that the two share a node).
    pub fn constant(&mut self, value: f64) -> Id {
        let value = if value == 0.0 { 0.0 } else { value };
        self.intern(Node::Const(value.to_bits()))
    }

    /// The value of a constant node.
    pub fn as_const(&self, id: Id) -> Option<f64> {
        match self.node(id) {
            Node::Const(bits) => Some(f64::from_bits(bits)),
            _ => None,
        }
    }

    fn is(&self, id: Id, value: f64) -> bool {
        self.as_const(id) == Some(value)
    }

    fn negated(&self, id: Id) -> Option<Id> {
        match self.node(id) {
            Node::Neg(x) => Some(x),
            _ => None,
        }
    }

    /// `a + b`, folded.
    pub fn add(&mut self, a: Id, b: Id) -> Id {
        if let (Some(x), Some(y)) = (self.as_const(a), self.as_const(b)) {
            return self.constant(x + y);
        }
        if self.is(a, 0.0) {
            return b;
        }
        if self.is(b, 0.0) {
            return a;
        }
        if let Some(y) = self.negated(b) {
            return self.sub(a, y);
        }
        if let Some(x) = self.negated(a) {
            return self.sub(b, x);
        }
        self.intern(Node::Add(a.min(b), a.max(b)))
    }

    /// `a − b`, folded.
    pub fn sub(&mut self, a: Id, b: Id) -> Id {
        if let (Some(x), Some(y)) = (self.as_const(a), self.as_const(b)) {
            return self.constant(x - y);
        }
        if a == b {
            return self.constant(0.0);
        }
        if self.is(b, 0.0) {
            return a;
        }
        if self.is(a, 0.0) {
            return self.neg(b);
        }
        if let Some(y) = self.negated(b) {
            return self.add(a, y);
        }
        if let Some(x) = self.negated(a) {
            // −x − b = −(x + b)
            let s = self.add(x, b);
            return self.neg(s);
        }
        self.intern(Node::Sub(a, b))
    }

    /// `a · b`, folded; negations are pulled outside so that `(−x)·y` and
    /// `x·(−y)` share the node `x·y`.
    pub fn mul(&mut self, a: Id, b: Id) -> Id {
        if let (Some(x), Some(y)) = (self.as_const(a), self.as_const(b)) {
            return self.constant(x * y);
        }
        if self.is(a, 0.0) || self.is(b, 0.0) {
            return self.constant(0.0);
        }
        if self.is(a, 1.0) {
            return b;
        }
        if self.is(b, 1.0) {
            return a;
        }
        if self.is(a, -1.0) {
            return self.neg(b);
        }
        if self.is(b, -1.0) {
            return self.neg(a);
        }
        if let Some(x) = self.negated(a) {
            let p = self.mul(x, b);
            return self.neg(p);
        }
        if let Some(y) = self.negated(b) {
            let p = self.mul(a, y);
            return self.neg(p);
        }
        self.intern(Node::Mul(a.min(b), a.max(b)))
    }

    /// `−a`, folded.
    pub fn neg(&mut self, a: Id) -> Id {
        if let Some(x) = self.as_const(a) {
            return self.constant(-x);
        }
        if let Some(x) = self.negated(a) {
            return x;
        }
        if let Node::Sub(x, y) = self.node(a) {
            return self.intern(Node::Sub(y, x));
        }
        self.intern(Node::Neg(a))
    }

    /// The nodes needed to compute `outputs`, in evaluation order. Leaves and
    /// constants are included; the emitter inlines them.
    pub fn reachable(&self, outputs: &[Id]) -> Vec<Id> {
        let mut live = vec![false; self.nodes.len()];
        for &o in outputs {
            live[o.index()] = true;
        }
        // Ids are topological, so one reverse sweep marks every dependency.
        for i in (0..self.nodes.len()).rev() {
            if !live[i] {
                continue;
            }
            match self.nodes[i] {
                Node::Add(a, b) | Node::Sub(a, b) | Node::Mul(a, b) => {
                    live[a.index()] = true;
                    live[b.index()] = true;
                }
                Node::Neg(a) => live[a.index()] = true,
                Node::Input(_) | Node::Const(_) => {}
            }
        }
        (0..self.nodes.len())
            .filter(|&i| live[i])
            .map(|i| Id(i as u32))
            .collect()
    }

    /// Counts of the arithmetic operations needed for `outputs`.
    pub fn op_count(&self, outputs: &[Id]) -> OpCount {
        let mut count = OpCount::default();
        for id in self.reachable(outputs) {
            match self.node(id) {
                Node::Add(..) | Node::Sub(..) => count.add_sub += 1,
                Node::Mul(..) => count.mul += 1,
                Node::Neg(..) => count.neg += 1,
                Node::Input(_) | Node::Const(_) => {}
            }
        }
        count
    }

    /// Evaluates every node numerically — the generator's own oracle, so the
    /// expressions are tested without compiling them.
    pub fn eval(&self, input: impl Fn(Input) -> f64) -> Vec<f64> {
        let mut v: Vec<f64> = Vec::with_capacity(self.nodes.len());
        for node in &self.nodes {
            let x = match *node {
                Node::Input(i) => input(i),
                Node::Const(bits) => f64::from_bits(bits),
                Node::Add(a, b) => v[a.index()] + v[b.index()],
                Node::Sub(a, b) => v[a.index()] - v[b.index()],
                Node::Mul(a, b) => v[a.index()] * v[b.index()],
                Node::Neg(a) => -v[a.index()],
            };
            v.push(x);
        }
        v
    }
}

/// Arithmetic operation counts of a set of outputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpCount {
    /// Additions and subtractions.
    pub add_sub: usize,
    /// Multiplications.
    pub mul: usize,
    /// Negations.
    pub neg: usize,
}

impl OpCount {
    /// All operations.
    pub fn total(&self) -> usize {
        self.add_sub + self.mul + self.neg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structural_zeros_and_ones_fold_away() {
        let mut g = Graph::new();
        let x = g.input(Input::A(0));
        let zero = g.constant(0.0);
        let one = g.constant(1.0);
        let m = g.mul(x, one);
        assert_eq!(g.mul(x, zero), zero);
        assert_eq!(m, x);
        assert_eq!(g.add(m, zero), x);
        assert_eq!(g.sub(x, x), zero);
        let minus_one = g.constant(-1.0);
        let n = g.mul(minus_one, x);
        assert_eq!(g.node(n), Node::Neg(x));
        assert_eq!(g.neg(n), x);
        assert_eq!(g.constant(-0.0), zero);
    }

    #[test]
    fn equal_subexpressions_share_one_node() {
        let mut g = Graph::new();
        let x = g.input(Input::CosQ(0));
        let y = g.input(Input::SinQ(0));
        let xy = g.mul(x, y);
        assert_eq!(g.mul(y, x), xy);
        let nx = g.neg(x);
        let p = g.mul(nx, y);
        assert_eq!(g.node(p), Node::Neg(xy));
        let s = g.add(y, p);
        assert_eq!(g.node(s), Node::Sub(y, xy));
        let before = g.nodes().len();
        g.add(x, y);
        g.add(y, x);
        assert_eq!(g.nodes().len(), before + 1);
    }

    #[test]
    fn eval_follows_the_folded_graph() {
        let mut g = Graph::new();
        let x = g.input(Input::A(0));
        let y = g.input(Input::D(0));
        let nx = g.neg(x);
        let a = g.sub(nx, y); // −x − y
        let b = g.mul(a, y);
        let v = g.eval(|i| if i == Input::A(0) { 2.0 } else { 3.0 });
        assert_eq!(v[a.index()], -5.0);
        assert_eq!(v[b.index()], -15.0);
    }

    #[test]
    fn reachable_drops_dead_nodes() {
        let mut g = Graph::new();
        let x = g.input(Input::A(0));
        let y = g.input(Input::D(0));
        let used = g.add(x, y);
        let _dead = g.mul(x, y);
        assert_eq!(g.reachable(&[used]), vec![x, y, used]);
        assert_eq!(
            g.op_count(&[used]),
            OpCount {
                add_sub: 1,
                mul: 0,
                neg: 0
            }
        );
    }
}
