((A B (left-front left-middle) C) (B C right-back D))
