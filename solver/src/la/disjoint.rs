//! Disjoint sets (union–find with path halving): the connected parts of a
//! graph given edge by edge, as the checks of anchored systems, rigid
//! parts and the sides of an interface need them.

/// Sets of `0..n`, merged by [`DisjointSets::join`].
#[derive(Clone, Debug)]
pub(crate) struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    /// `n` singletons.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    /// The representative of `a`'s set (halving the path on the way).
    pub(crate) fn root(&mut self, mut a: usize) -> usize {
        while self.parent[a] != a {
            self.parent[a] = self.parent[self.parent[a]];
            a = self.parent[a];
        }
        a
    }

    /// Merge the sets of `a` and `b`.
    pub(crate) fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        self.parent[ra] = rb;
    }
}

#[cfg(test)]
mod tests {
    use super::DisjointSets;

    #[test]
    fn joined_elements_share_a_root_and_others_do_not() {
        // 0–1–2 and 3–4 joined, 5 alone: three sets.
        let mut sets = DisjointSets::new(6);
        sets.join(0, 1);
        sets.join(2, 1);
        sets.join(3, 4);
        let roots: Vec<usize> = (0..6).map(|i| sets.root(i)).collect();
        assert_eq!(roots[0], roots[1]);
        assert_eq!(roots[1], roots[2]);
        assert_eq!(roots[3], roots[4]);
        assert_ne!(roots[0], roots[3]);
        assert_ne!(roots[5], roots[0]);
        assert_ne!(roots[5], roots[3]);
    }
}
