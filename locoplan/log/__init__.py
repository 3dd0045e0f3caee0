"""locoplan.log"""
