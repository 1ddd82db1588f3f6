(def-calculus "Point Algebra"
  :arity :binary
  :identity-relation =
  :converse-operation ((< >) (= =) (> <))
  :base-relations (< = >)
  :composition-operation ((< < <) (< = <) (< > (< = >)) (= < <) (= = =) (= > >)
                          (> < (< = >)) (> = >) (> > >)))
